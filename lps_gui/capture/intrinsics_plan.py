"""Guided intrinsics capture with a hand-held board: a list of varied poses to hold, checked and stored.

Intrinsics are only determined by views that differ (SPEC 6): the board near
each image corner and edge so the distortion is seen, and tilted ~30 deg
about both axes so the focal length separates from the distance. The plan
is a fixed list of :class:`PoseGoal` (where in the image, which tilt); the
operator holds the board as told and :class:`IntrinsicsCapture` grabs, checks
that the board is seen where asked, and stores the image atomically with a
line in ``intrinsics_captures.jsonl``, so an interrupted set resumes. The
folder is the input of ``lps intrinsics FOLDER``.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from lps_gui.camera.base import Camera
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.io.atomic import append_line_durable, check_writable, sha256_bytes, write_bytes_atomic

LIST_FILE = "intrinsics_captures.jsonl"
TILT_DEG = 30.0
Detector = Callable[[np.ndarray, Board], "np.ndarray | None"]


@dataclass(frozen=True)
class PoseGoal:
    """One view to take: the board inside ``region`` (fractions of the image) with a tilt."""

    name: str
    instruction: str
    region: tuple[float, float, float, float]  # x0, y0, x1, y1 as fractions of width and height
    tilt_deg: tuple[float, float]  # about the image x axis (top away: +), about the image y axis (right away: +)

    @property
    def centre(self) -> tuple[float, float]:
        x0, y0, x1, y1 = self.region
        return (0.5 * (x0 + x1), 0.5 * (y0 + y1))


_PLACES = {
    "centre": ("in the middle", (0.2, 0.2, 0.8, 0.8)),
    "top-left": ("in the top-left corner", (0.0, 0.0, 0.55, 0.55)),
    "top-right": ("in the top-right corner", (0.45, 0.0, 1.0, 0.55)),
    "bottom-left": ("in the bottom-left corner", (0.0, 0.45, 0.55, 1.0)),
    "bottom-right": ("in the bottom-right corner", (0.45, 0.45, 1.0, 1.0)),
    "top": ("along the top edge", (0.2, 0.0, 0.8, 0.5)),
    "bottom": ("along the bottom edge", (0.2, 0.5, 0.8, 1.0)),
    "left": ("along the left edge", (0.0, 0.2, 0.5, 0.8)),
    "right": ("along the right edge", (0.5, 0.2, 1.0, 0.8)),
}
_TILTS = {
    "flat": ("facing the camera", (0.0, 0.0)),
    "left": (f"turned ~{TILT_DEG:g} deg, left side away", (0.0, -TILT_DEG)),
    "right": (f"turned ~{TILT_DEG:g} deg, right side away", (0.0, TILT_DEG)),
    "up": (f"tipped ~{TILT_DEG:g} deg, top away", (TILT_DEG, 0.0)),
    "down": (f"tipped ~{TILT_DEG:g} deg, bottom away", (-TILT_DEG, 0.0)),
}
_ORDER = [
    ("centre", "flat"), ("centre", "left"), ("centre", "right"), ("centre", "up"), ("centre", "down"),
    ("top-left", "flat"), ("top-right", "flat"), ("bottom-left", "flat"), ("bottom-right", "flat"),
    ("top-left", "right"), ("bottom-right", "left"), ("top-right", "down"), ("bottom-left", "up"),
    ("top", "down"), ("bottom", "up"), ("left", "right"), ("right", "left"),
    ("top", "flat"), ("bottom", "flat"), ("left", "flat"), ("right", "flat"),
]


def intrinsics_plan(n_views: int = 15) -> list[PoseGoal]:
    """``n_views`` (4..21) varied poses: centre with four tilts first, then corners and edges."""
    n = int(np.clip(n_views, 4, len(_ORDER)))
    goals = []
    for place, tilt in _ORDER[:n]:
        where, region = _PLACES[place]
        how, tilt_deg = _TILTS[tilt]
        goals.append(PoseGoal(f"{place}-{tilt}", f"hold the board {where}, {how}", region, tilt_deg))
    return goals


def goal_pose(goal: PoseGoal, board: Board, intrinsics: CameraIntrinsics, fill: float = 0.7) -> tuple[np.ndarray, np.ndarray]:
    """A board pose (R_cam_board (3, 3), t_cam_board (3,) mm) that satisfies ``goal``.

    The board centre sits on the ray through the region's centre, tilted as
    asked, at the distance where its width spans ``fill`` of the region
    width. Used to simulate a hand-held board and to draw a guide overlay.
    """
    import cv2

    w, h = intrinsics.image_size
    cx, cy = goal.centre
    ray = cv2.undistortPoints(
        np.array([[[cx * (w - 1), cy * (h - 1)]]]), intrinsics.camera_matrix, intrinsics.cv_dist
    ).reshape(2)
    x0, _, x1, _ = goal.region
    width_mm = board.square_mm * (board.cols - 1)
    distance_mm = intrinsics.camera_matrix[0, 0] * width_mm / max(fill * (x1 - x0) * w, 1.0)
    a, b = np.deg2rad(goal.tilt_deg)
    R = exp_so3(np.array([a, 0.0, 0.0])) @ exp_so3(np.array([0.0, b, 0.0]))
    centre_cam = distance_mm * np.array([ray[0], ray[1], 1.0])
    t = centre_cam - R @ board.centre_mm()
    return R, t


@dataclass(frozen=True)
class PoseCheck:
    """How a grabbed view compares with its goal."""

    found: bool
    ok: bool
    message: str
    corners_px: np.ndarray | None = None  # shape (N, 2)


def check_view(corners_px: np.ndarray | None, goal: PoseGoal, image_size: tuple[int, int]) -> PoseCheck:
    """Is the board seen, and is its centre near the centre of the goal's region?

    The tilt cannot be measured without intrinsics; it is left to the
    operator's eye (the instruction says which side goes away).
    """
    if corners_px is None or not np.isfinite(corners_px).all():
        return PoseCheck(False, False, "board not found: hold it still, fully in view, and avoid glare")
    w, h = image_size
    centre = np.nanmean(corners_px, axis=0) / np.array([w, h], dtype=float)
    x0, y0, x1, y1 = goal.region
    tolerance = np.maximum(0.12, 0.25 * np.array([x1 - x0, y1 - y0]))  # fractions of the image
    if (np.abs(centre - np.array(goal.centre)) > tolerance).any():
        return PoseCheck(True, False, f"board seen but not where asked: {goal.instruction}", corners_px)
    return PoseCheck(True, True, "good view", corners_px)


class IntrinsicsCapture:
    """Take the views of an intrinsics plan from ``camera`` into ``folder``; resumable.

    Parameters
    ----------
    camera : an opened :class:`Camera`.
    folder : where images and ``intrinsics_captures.jsonl`` go (created).
    board : the hand-held board.
    goals : the plan; :func:`intrinsics_plan` when None.
    detect : ``detect(image, board) -> corners (N, 2) | None``;
        :func:`lps_gui.camera.detection.detect_chessboard` when None.
    """

    def __init__(
        self,
        camera: Camera,
        folder: Path | str,
        board: Board,
        goals: list[PoseGoal] | None = None,
        detect: Detector | None = None,
    ) -> None:
        self.camera = camera
        self.folder = Path(folder)
        self.board = board
        self.goals = goals if goals is not None else intrinsics_plan()
        if detect is None:
            from lps_gui.camera.detection import detect_chessboard

            detect = detect_chessboard
        self.detect = detect
        check_writable(self.folder)
        self.taken: dict[str, dict[str, Any]] = self._read_list()

    def _read_list(self) -> dict[str, dict[str, Any]]:
        path = self.folder / LIST_FILE
        out: dict[str, dict[str, Any]] = {}
        if path.exists():
            for line in path.read_text(encoding="utf-8").splitlines():
                try:
                    d = json.loads(line)
                    out[str(d["goal"])] = d
                except (json.JSONDecodeError, KeyError, TypeError):
                    continue  # torn by a crash: that view is taken again
        return out

    def current(self) -> PoseGoal | None:
        """The next goal not yet taken, or None when the plan is complete."""
        return next((g for g in self.goals if g.name not in self.taken), None)

    @property
    def done(self) -> bool:
        return self.current() is None

    def take(self, force: bool = False) -> PoseCheck:
        """Grab a view for the current goal; store it when it passes the check (or ``force``)."""
        from lps_gui.capture.engine import encode_image

        goal = self.current()
        if goal is None:
            return PoseCheck(False, False, "every view of the plan is taken; run `lps intrinsics` on the folder")
        frame = self.camera.grab()
        result = check_view(self.detect(frame.image, self.board), goal, frame.size)
        if not (result.ok or force and result.found):
            return result
        data = encode_image(frame.image, ".png")
        name = f"intr_{self.goals.index(goal):02d}_{goal.name}.png"
        write_bytes_atomic(self.folder / name, data)
        line = {"goal": goal.name, "file": name, "sha256": sha256_bytes(data), "ok": result.ok, "message": result.message}
        append_line_durable(self.folder / LIST_FILE, json.dumps(line, separators=(",", ":")))
        self.taken[goal.name] = line
        return result

    def skip(self) -> None:
        """Move past the current goal without an image (listed as skipped)."""
        goal = self.current()
        if goal is not None:
            line = {"goal": goal.name, "file": None, "sha256": None, "ok": False, "message": "skipped"}
            append_line_durable(self.folder / LIST_FILE, json.dumps(line, separators=(",", ":")))
            self.taken[goal.name] = line


def coverage(corners: list[np.ndarray], image_size: tuple[int, int], cells: tuple[int, int] = (8, 6)) -> float:
    """Fraction of an image grid (``cells`` columns x rows) holding at least one corner of ``corners``."""
    w, h = image_size
    hit = np.zeros(cells[::-1], dtype=bool)
    for c in corners:
        c = c[np.isfinite(c).all(axis=1)]
        ix = np.clip((c[:, 0] / w * cells[0]).astype(int), 0, cells[0] - 1)
        iy = np.clip((c[:, 1] / h * cells[1]).astype(int), 0, cells[1] - 1)
        hit[iy, ix] = True
    return float(hit.mean())
