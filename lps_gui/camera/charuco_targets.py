"""Every target of a row or constellation in one image (SPEC 13).

One ArUco marker pass per dictionary finds all markers; they are split by the
targets' id ranges, and each target's ChArUco corners are interpolated from its
own markers and refined like a single board's. A target seen only in part
keeps the corners it has (a row's end targets are usually cut by the image
border), down to :data:`MIN_CORNERS`.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lps_gui.camera.charuco import DEFAULT_DICTIONARY, MIN_CORNERS, aruco_board, grey, refined_corners
from lps_gui.core.geometry.targets import Target


@dataclass(frozen=True)
class TargetCorners:
    """The corners of one target in one image: corner numbers (r * cols + c) and pixels (n, 2)."""

    target: str
    corner: np.ndarray
    xy: np.ndarray


def _dictionary(name: str | None) -> "cv2.aruco.Dictionary":
    return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name or DEFAULT_DICTIONARY))


def detect_targets(image: np.ndarray, targets: list[Target]) -> list[TargetCorners]:
    """The targets found in ``image``, in the order of ``targets``; a target not found is left out."""
    image = grey(image)
    found: list[TargetCorners] = []
    by_dict: dict[str, list[Target]] = {}
    for t in targets:
        by_dict.setdefault(t.board.dictionary or DEFAULT_DICTIONARY, []).append(t)
    per_target: dict[str, TargetCorners] = {}
    for name, group in by_dict.items():
        detector = cv2.aruco.ArucoDetector(_dictionary(name), cv2.aruco.DetectorParameters())
        marker_corners, marker_ids, _ = detector.detectMarkers(image)
        if marker_ids is None or len(marker_ids) == 0:
            continue
        ids = marker_ids.ravel()
        for t in group:
            mine = (ids >= t.first_marker) & (ids < t.first_marker + t.n_markers)
            if mine.sum() < 2:
                continue
            board = aruco_board(t.board, t.first_marker)
            charuco = cv2.aruco.CharucoDetector(board)
            corners, cids, _, _ = charuco.detectBoard(
                image, markerCorners=tuple(c for c, m in zip(marker_corners, mine) if m),
                markerIds=marker_ids[mine].reshape(-1, 1))
            if cids is None or len(cids) < MIN_CORNERS:
                continue
            xy = refined_corners(image, t.board, cids, corners)
            seen = np.flatnonzero(np.isfinite(xy[:, 0]))
            per_target[t.id] = TargetCorners(t.id, seen, xy[seen])
    for t in targets:
        if t.id in per_target:
            found.append(per_target[t.id])
    return found


def dense_corners(found: list[TargetCorners], targets: list[Target]) -> dict[str, np.ndarray]:
    """Each target's corners as a (n_corners, 2) array with NaN where not seen (all targets present)."""
    out = {t.id: np.full((t.board.n_corners, 2), np.nan) for t in targets}
    for f in found:
        out[f.target][f.corner] = f.xy
    return out


def detect_targets_dense(image: np.ndarray, targets: list[Target]) -> np.ndarray | None:
    """Every target's corners laid end to end (sum of n_corners, 2), NaN where not seen; None when no target
    was found (what a corners.vnl row of a session with targets holds)."""
    found = detect_targets(image, targets)
    if not found:
        return None
    per = dense_corners(found, targets)
    return np.concatenate([per[t.id] for t in targets]).astype(np.float32)
