"""Writers of COLMAP's text model, nerfstudio's transforms.json and our pose CSV (SPEC 12).

COLMAP (colmap.github.io/format.html): ``cameras.txt`` ``CAMERA_ID MODEL WIDTH
HEIGHT PARAMS[]`` (FULL_OPENCV: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6),
``images.txt`` two lines per image (``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID
NAME``, then the 2-D points, empty here), ``points3D.txt`` ``POINT3D_ID X Y Z
R G B ERROR TRACK[]`` (the board's corners, no track). nerfstudio
(docs.nerf.studio, data conventions): ``transforms.json`` with shared
intrinsics at the top and ``frames[{file_path, transform_matrix}]``.
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.models.export_poses import PIXEL_CENTRE_SHIFT, camera_to_world_opengl, rotation_to_quaternion
from lps_gui.io.atomic import write_text_atomic
from lps_gui.io.file_set import write_file_set
from lps_gui.io.results.keys import MEASURED_MM

POSES_CSV_COLUMNS = ("index", "run", "direction", "file", "target_mm", MEASURED_MM,
                     "nominal_x_mm", "nominal_y_mm", "nominal_z_mm", "measured_x_mm", "measured_y_mm", "measured_z_mm")


def _shifted(intr: CameraIntrinsics) -> tuple[float, float, float, float]:
    return intr.fx, intr.fy, intr.cx + PIXEL_CENTRE_SHIFT, intr.cy + PIXEL_CENTRE_SHIFT


def write_colmap(folder: Path, intr: CameraIntrinsics, R: np.ndarray, t: np.ndarray, names: Sequence[str],
                 board_points: np.ndarray) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    fx, fy, cx, cy = _shifted(intr)
    k1, k2, p1, p2, k3 = (float(v) for v in intr.dist)
    w, h = intr.image_size
    cams = ("# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
            f"# Number of cameras: 1\n1 FULL_OPENCV {w} {h} {fx!r} {fy!r} {cx!r} {cy!r} {k1!r} {k2!r} {p1!r} {p2!r} {k3!r} 0 0 0\n")
    q = rotation_to_quaternion(R)
    lines = ["# Image list with two lines of data per image:",
             "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
             "#   POINTS2D[] as (X, Y, POINT3D_ID)",
             f"# Number of images: {len(names)}"]
    for k, (ti, name) in enumerate(zip(t, names), start=1):
        lines.append(" ".join([str(k), *(repr(float(v)) for v in q), *(repr(float(v)) for v in ti), "1", name]))
        lines.append("")
    pts = ["# 3D point list with one line of data per point:",
           "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)",
           f"# Number of points: {len(board_points)}"]
    pts += [f"{k} {X!r} {Y!r} {Z!r} 255 255 255 0" for k, (X, Y, Z) in enumerate(board_points.tolist(), start=1)]
    texts = {"cameras.txt": cams, "points3D.txt": "\n".join(pts) + "\n", "images.txt": "\n".join(lines) + "\n"}
    # one set: a kill or a full disk over an older export leaves the old three files or the new three, never a mix
    write_file_set(folder, {name: text.encode("utf-8") for name, text in texts.items()}, last="images.txt")
    return [folder / "cameras.txt", folder / "images.txt", folder / "points3D.txt"]


def write_nerfstudio(folder: Path, intr: CameraIntrinsics, R: np.ndarray, centres: np.ndarray, names: Sequence[str],
                     image_root: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    fx, fy, cx, cy = _shifted(intr)
    k1, k2, p1, p2, k3 = (float(v) for v in intr.dist)
    doc: dict[str, Any] = {
        "camera_model": "OPENCV", "fl_x": fx, "fl_y": fy, "cx": cx, "cy": cy,
        "w": int(intr.image_size[0]), "h": int(intr.image_size[1]),
        "k1": k1, "k2": k2, "k3": k3, "p1": p1, "p2": p2,
        "frames": [{"file_path": f"{image_root}/{name}", "transform_matrix": camera_to_world_opengl(R, C).tolist()}
                   for name, C in zip(names, centres)],
    }
    path = folder / "transforms.json"
    write_text_atomic(path, json.dumps(doc, indent=1) + "\n")
    return path


def write_poses_csv(path: Path, rows: list[dict[str, Any]]) -> Path:
    buf = io.StringIO()
    w = csv.DictWriter(buf, POSES_CSV_COLUMNS, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.6f}" if isinstance(v, float) else v) for k, v in r.items()})
    write_text_atomic(path, buf.getvalue())
    return path
