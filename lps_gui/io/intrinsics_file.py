"""intrinsics.json and OpenCV FileStorage YAML (SPEC 7).

JSON: ``{"image_size": [w, h], "camera_matrix": 3x3, "dist": [k1,k2,p1,p2,k3]`` (12 coefficients,
OpenCV's order, when the lens has rational and thin-prism terms)``,
"std": {"fx": .., ...}, "rms_px": x, "n_views": n}``, optionally a full
``"covariance"`` (9x9 in ``covariance_order``), and when the calibration
estimated the board's bow ``"board_warp_mm": [bow_x, bow_y]`` with
``"board_warp_sigma_mm"`` (see :class:`Board`; the LPS estimate then uses the
bowed board, :func:`apply_board_warp`). YAML: OpenCV's
``camera_matrix``, ``distortion_coefficients``, ``image_width``,
``image_height``, plus our ``std_intrinsics`` when known. ``.cameramodel``: mrcal's format
(:mod:`lps_gui.io.cameramodel_file`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_text_atomic
from lps_gui.io.cameramodel_file import SUFFIX as CAMERAMODEL_SUFFIX
from lps_gui.io.cameramodel_file import read_cameramodel, write_cameramodel
from lps_gui.io.image_file import check_regular_file, read_file_limited
from lps_gui.io.jsonfile import read_json, write_json
from lps_gui.io.value_checks import check_intrinsics_values

YAML_SUFFIXES = (".yaml", ".yml", ".xml")


def intrinsics_from_dict(d: dict[str, Any], source: str = "intrinsics") -> CameraIntrinsics:
    check_intrinsics_values(d, source)
    try:
        K = np.asarray(d["camera_matrix"], dtype=float).reshape(3, 3)
        dist = np.asarray(d.get("dist", [0.0] * 5), dtype=float).ravel()
        size = tuple(int(v) for v in d["image_size"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{source}: needs image_size [w, h], camera_matrix 3x3 and dist [k1,k2,p1,p2,k3] ({exc})") from exc
    if not np.all(np.isfinite(K)) or not np.all(np.isfinite(dist)) or K[0, 0] <= 0 or K[1, 1] <= 0:
        raise InputError(f"{source}: camera_matrix must be finite with positive focal lengths; recalibrate")
    cov = None
    if d.get("covariance") is not None:
        order = tuple(d.get("covariance_order", INTRINSIC_NAMES))
        if order != INTRINSIC_NAMES:
            raise InputError(f"{source}: covariance_order must be {list(INTRINSIC_NAMES)}")
        try:
            cov = np.asarray(d["covariance"], dtype=float).reshape(9, 9)
        except (TypeError, ValueError):
            raise InputError(f"{source}: covariance must be a 9x9 matrix of numbers; recalibrate") from None
        if not np.isfinite(cov).all() or (np.diag(cov) < 0).any() or not np.allclose(cov, cov.T, rtol=1e-6, atol=0.0):
            raise InputError(f"{source}: covariance must be finite and symmetric with no negative variance (a "
                             "variance is a squared sigma); recalibrate")
    elif d.get("std"):
        std = d["std"]
        cov = np.diag([float(std.get(name, 0.0)) ** 2 for name in INTRINSIC_NAMES])
    extra = {k: v for k, v in d.items() if k not in ("image_size", "camera_matrix", "dist", "std", "covariance", "covariance_order", "rms_px", "n_views")}
    return CameraIntrinsics(
        image_size=size,  # type: ignore[arg-type]
        camera_matrix=K,
        dist=dist,
        covariance=cov,
        rms_px=None if d.get("rms_px") is None else float(d["rms_px"]),
        n_views=None if d.get("n_views") is None else int(d["n_views"]),
        extra=extra,
    )


def intrinsics_to_dict(intr: CameraIntrinsics) -> dict[str, Any]:
    d: dict[str, Any] = {
        "image_size": list(intr.image_size),
        "camera_matrix": intr.camera_matrix.tolist(),
        "dist": intr.cv_dist.tolist(),
    }
    std = intr.std()
    if std is not None:
        d["std"] = {name: float(v) for name, v in zip(INTRINSIC_NAMES, std)}
        if np.count_nonzero(intr.covariance - np.diag(np.diag(intr.covariance))):
            d["covariance_order"] = list(INTRINSIC_NAMES)
            d["covariance"] = intr.covariance.tolist()
    d["rms_px"] = intr.rms_px
    d["n_views"] = intr.n_views
    d.update(intr.extra)
    return d


def model_error_covariance(intr: CameraIntrinsics | None) -> np.ndarray | None:
    """The lens-model part of ``covariance`` (``model_error.covariance``, 9x9 in INTRINSIC_NAMES order, written by a
    calibration that measured it: :mod:`lps_gui.core.intrinsics.model_error`), None when the file has none."""
    rec = None if intr is None else intr.extra.get("model_error")
    if not isinstance(rec, dict) or rec.get("covariance") is None:
        return None
    try:
        cov = np.asarray(rec["covariance"], dtype=float).reshape(9, 9)
    except (TypeError, ValueError):
        raise InputError("intrinsics: model_error.covariance must be a 9x9 matrix of numbers; recalibrate") from None
    if not np.isfinite(cov).all() or (np.diag(cov) < 0).any():
        raise InputError("intrinsics: model_error.covariance must be finite with no negative variance; recalibrate")
    return cov


def apply_board_warp(board: Board, intr: CameraIntrinsics | None) -> Board:
    """The board as the intrinsics calibration found it: bowed by ``board_warp_mm`` when that is known."""
    from dataclasses import replace

    warp = None if intr is None else intr.extra.get("board_warp_mm")
    if warp is None:
        return board
    try:
        return replace(board, warp_mm=(float(warp[0]), float(warp[1])))
    except (TypeError, ValueError, IndexError) as exc:
        raise InputError(f"intrinsics: board_warp_mm must be [bow_x, bow_y] in mm, got {warp!r}") from exc


MAX_INTRINSICS_BYTES = 16 << 20  # a calibration with per-view figures of 10000 views is a few MB


def read_intrinsics(path: Path | str, follow_symlinks: bool = True) -> CameraIntrinsics:
    """Read intrinsics from JSON, OpenCV YAML/XML or mrcal .cameramodel (chosen by suffix).

    The file must be a regular one (a FIFO would block the read for ever); ``follow_symlinks=False`` for a
    file a session names.
    """
    path = Path(path)
    if path.suffix.lower() == CAMERAMODEL_SUFFIX:
        check_regular_file(path, "intrinsics file", follow_symlinks)
        return read_cameramodel(path)
    if path.suffix.lower() in YAML_SUFFIXES:
        return _read_opencv_yaml(path, read_file_limited(path, MAX_INTRINSICS_BYTES, "intrinsics file", follow_symlinks))
    return intrinsics_from_dict(read_json(path, "intrinsics file", follow_symlinks), str(path))


def write_intrinsics(path: Path | str, intr: CameraIntrinsics) -> None:
    path = Path(path)
    if path.suffix.lower() == CAMERAMODEL_SUFFIX:
        write_cameramodel(path, intr)
    elif path.suffix.lower() in YAML_SUFFIXES:
        _write_opencv_yaml(path, intr)
    else:
        write_json(path, intrinsics_to_dict(intr))


def _read_opencv_yaml(path: Path, data: bytes) -> CameraIntrinsics:
    """The intrinsics of OpenCV FileStorage text ``data`` (read by the caller: limits checked, no FIFO)."""
    import cv2

    try:
        text = data.decode("utf-8")
        fs = cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)
        try:
            K = fs.getNode("camera_matrix").mat()
            dist = fs.getNode("distortion_coefficients").mat()
            w = fs.getNode("image_width").real()
            h = fs.getNode("image_height").real()
            std = fs.getNode("std_intrinsics").mat()
            rms = fs.getNode("rms_px").real()
        finally:
            fs.release()
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (binary content); give OpenCV calibration YAML") from None
    except (cv2.error, SystemError, ValueError) as exc:  # garbage YAML: cv2.error or a SystemError from its binding
        why = (str(exc).strip().splitlines() or [type(exc).__name__])[-1]
        raise InputError(f"{path}: not an OpenCV FileStorage file ({why[:120]})") from None
    if K is None or dist is None:
        raise InputError(f"{path}: needs camera_matrix and distortion_coefficients nodes (OpenCV calibration YAML)")
    d: dict[str, Any] = {"image_size": [int(w), int(h)], "camera_matrix": K, "dist": dist.ravel()}
    if std is not None:
        d["std"] = dict(zip(INTRINSIC_NAMES, std.ravel().tolist()))
    if rms:
        d["rms_px"] = rms
    return intrinsics_from_dict(d, str(path))


def _write_opencv_yaml(path: Path, intr: CameraIntrinsics) -> None:
    import tempfile

    import cv2

    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp) / path.name
        fs = cv2.FileStorage(str(tmp_path), cv2.FILE_STORAGE_WRITE)
        fs.write("image_width", int(intr.image_size[0]))
        fs.write("image_height", int(intr.image_size[1]))
        fs.write("camera_matrix", intr.camera_matrix)
        fs.write("distortion_coefficients", intr.cv_dist.reshape(1, -1))
        std = intr.std()
        if std is not None:
            fs.write("std_intrinsics", std.reshape(1, 9))
        if intr.rms_px is not None:
            fs.write("rms_px", float(intr.rms_px))
        fs.release()
        write_text_atomic(path, tmp_path.read_text())
