"""mrcal's ``.cameramodel`` files, so a calibration moves between mrcal and lps.

The format (mrcal docs, "cameramodel file formats") is one Python literal
dict, comments allowed: ``lensmodel`` (a string such as
``'LENSMODEL_OPENCV8'``), ``intrinsics`` (fx, fy, cx, cy, then the
distortion coefficients in OpenCV's order k1, k2, p1, p2, k3, k4, k5, k6),
``extrinsics`` (rt_fromref: Rodrigues vector then translation, 6 numbers)
and ``imagersize`` [width, height]; optionally ``valid_intrinsics_region``,
``icam_intrinsics`` and the binary ``optimization_inputs`` (read past).

Our camera model is OpenCV's with the rational and thin-prism terms, so we
read LENSMODEL_PINHOLE, OPENCV4, OPENCV5, OPENCV8 and OPENCV12, and write
OPENCV5, OPENCV8 or OPENCV12 (a lens with higher terms is written as OPENCV12). Our standard
deviations and the board's bow go into comments (mrcal keeps no such keys;
the uncertainty mrcal computes lives in ``optimization_inputs``).
"""
from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_text_atomic

SUFFIX = ".cameramodel"
# lens model -> number of distortion coefficients (OpenCV order)
LENSMODELS = {"LENSMODEL_PINHOLE": 0, "LENSMODEL_OPENCV4": 4, "LENSMODEL_OPENCV5": 5, "LENSMODEL_OPENCV8": 8,
              "LENSMODEL_OPENCV12": 12}
WRITABLE = ("LENSMODEL_OPENCV5", "LENSMODEL_OPENCV8", "LENSMODEL_OPENCV12")


def parse_cameramodel(text: str, source: str = "cameramodel") -> CameraIntrinsics:
    """Intrinsics from the text of a .cameramodel file."""
    try:
        d = ast.literal_eval(text)
    except (SyntaxError, ValueError) as exc:
        raise InputError(f"{source}: not an mrcal .cameramodel (a Python literal dict): {exc}") from exc
    if not isinstance(d, dict):
        raise InputError(f"{source}: not an mrcal .cameramodel (expected a dict)")
    missing = [k for k in ("lensmodel", "intrinsics", "imagersize") if k not in d]
    if missing:
        raise InputError(f"{source}: .cameramodel lacks {', '.join(missing)}")
    model = d["lensmodel"]
    if model not in LENSMODELS:
        raise InputError(f"{source}: lens model {model!r} is not supported; convert it with "
                         f"mrcal-convert-lensmodel to one of {', '.join(LENSMODELS)}")
    try:
        v = np.asarray(d["intrinsics"], dtype=float).ravel()
        w, h = (int(x) for x in d["imagersize"])
    except (TypeError, ValueError) as exc:
        raise InputError(f"{source}: intrinsics and imagersize must be lists of numbers ({exc})") from exc
    n = LENSMODELS[model]
    if v.size != 4 + n:
        raise InputError(f"{source}: {model} needs {4 + n} intrinsics, the file has {v.size}")
    dist = np.zeros(12)
    dist[:n] = v[4:]
    if not np.all(np.isfinite(v)) or v[0] <= 0 or v[1] <= 0:
        raise InputError(f"{source}: intrinsics must be finite with positive focal lengths")
    return CameraIntrinsics.from_values((w, h), *v[:4], dist=tuple(dist))


def format_cameramodel(intr: CameraIntrinsics, lensmodel: str = "LENSMODEL_OPENCV5") -> str:
    """The text of a .cameramodel file for ``intr`` (camera at the reference: extrinsics zero)."""
    if lensmodel not in WRITABLE:
        raise InputError(f"cameramodel: can write {', '.join(WRITABLE)}, not {lensmodel!r}")
    if intr.has_higher and lensmodel != "LENSMODEL_OPENCV12":
        lensmodel = "LENSMODEL_OPENCV8" if not np.any(intr.higher[3:]) else "LENSMODEL_OPENCV12"
    coeffs = list(np.concatenate([intr.dist, intr.higher])[: LENSMODELS[lensmodel]])
    values = [intr.fx, intr.fy, intr.cx, intr.cy, *coeffs]
    from lps_gui import __version__  # importlib.metadata: only when a file is written

    lines = [f"# written by lps-calib {__version__}"]
    std = intr.std()
    if std is not None:
        lines.append("# std: " + ", ".join(f"{n} {s:.6g}" for n, s in zip(INTRINSIC_NAMES, std)))
    if intr.rms_px is not None:
        lines.append(f"# rms reprojection error {intr.rms_px:.6g} px over {intr.n_views} views")
    if intr.extra.get("board_warp_mm") is not None:
        bow, sig = intr.extra["board_warp_mm"], intr.extra.get("board_warp_sigma_mm") or [float("nan")] * 2
        lines.append(f"# board warp (mrcal calobject_warp) {bow[0]:.6g} +- {sig[0]:.3g}, {bow[1]:.6g} +- {sig[1]:.3g} mm")
    lines += [
        "{",
        f"    'lensmodel':  '{lensmodel}',",
        "",
        "    # intrinsics are fx,fy,cx,cy,distortion0,distortion1,....",
        "    'intrinsics': [ " + " ".join(f"{x!r}," for x in map(float, values)) + "],",
        "",
        "    # extrinsics are rt_fromref",
        "    'extrinsics': [ 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,],",
        "",
        f"    'imagersize': [ {int(intr.image_size[0])}, {int(intr.image_size[1])},],",
        "}",
    ]
    return "\n".join(lines) + "\n"


def read_cameramodel(path: Path | str) -> CameraIntrinsics:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: intrinsics file not found; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the .cameramodel ({exc})") from exc
    return parse_cameramodel(text, str(path))


def write_cameramodel(path: Path | str, intr: CameraIntrinsics, lensmodel: str = "LENSMODEL_OPENCV5") -> None:
    write_text_atomic(path, format_cameramodel(intr, lensmodel))
