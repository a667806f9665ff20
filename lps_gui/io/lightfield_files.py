"""Files of a light field (SPEC 17): lightfield.json, the HCI 4D light field benchmark layout, view images.

HCI layout (the benchmark's own description: parameters.cfg, an INI file with sections ``intrinsics``
(image_resolution_x_px, image_resolution_y_px, focal_length_mm, sensor_size_mm, fstop), ``extrinsics``
(num_cams_x, num_cams_y, baseline_mm, focus_distance_m, center_cam_x_m, center_cam_y_m, center_cam_z_m,
center_cam_rx_rad, center_cam_ry_rad, center_cam_rz_rad) and ``meta`` (disp_min, disp_max,
frustum_disp_min, frustum_disp_max, depth_map_scale, scene, category, date, version, authors, contact);
the views ``input_Cam000.png``... numbered row-major from the top-left view, num_cams_x views a row). The
sensor size is the larger image side in mm, so f_px = focal_length_mm / sensor_size_mm * max(w, h).
Rectified views are not shifted towards a focus plane, so the focus distance is infinite (``inf``).
"""
from __future__ import annotations

import configparser
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lps_gui.errors import InputError
from lps_gui.file_limits import read_file_limited
from lps_gui.io.atomic import write_bytes_atomic, write_text_atomic
from lps_gui.io.jsonfile import write_json

LIGHTFIELD_FILE = "lightfield.json"
FORMAT = "lps-lightfield/1"
HCI_PARAMETERS = "parameters.cfg"
HCI_VIEW = "input_Cam{:03d}.png"


def write_png(path: Path, image: np.ndarray) -> None:
    """A lossless 8-bit PNG, written atomically (a view is either whole or absent)."""
    ok, buf = cv2.imencode(".png", image)
    if not ok:
        raise InputError(f"{path}: the image could not be encoded as PNG")
    write_bytes_atomic(path, buf.tobytes())


def write_lightfield_json(folder: Path, doc: dict[str, Any]) -> Path:
    path = folder / LIGHTFIELD_FILE
    write_json(path, {"format": FORMAT, **doc})
    return path


@dataclass(frozen=True)
class HciParameters:
    """What parameters.cfg says, as the benchmark's description names it."""

    width: int
    height: int
    focal_length_mm: float
    sensor_size_mm: float
    num_cams_x: int
    num_cams_y: int
    baseline_mm: float
    focus_distance_m: float
    raw: dict[str, dict[str, str]]

    @property
    def focal_px(self) -> float:
        return self.focal_length_mm / self.sensor_size_mm * max(self.width, self.height)


def write_hci_parameters(folder: Path, *, image_size: tuple[int, int], focal_px: float, pixel_mm: float,
                         shape: tuple[int, int], baseline_mm: float, centre_m: np.ndarray, rotation_rad: np.ndarray,
                         scene: str, date: str, version: str, disparity: tuple[float, float] | None) -> Path:
    """parameters.cfg of a ``shape`` = (num_cams_x, num_cams_y) light field."""
    w, h = image_size
    d0, d1 = disparity if disparity is not None else (0.0, 0.0)
    cfg = configparser.ConfigParser()
    cfg["intrinsics"] = {"image_resolution_x_px": str(w), "image_resolution_y_px": str(h),
                         "focal_length_mm": repr(focal_px * pixel_mm), "sensor_size_mm": repr(max(w, h) * pixel_mm),
                         "fstop": "100"}
    cfg["extrinsics"] = {"num_cams_x": str(shape[0]), "num_cams_y": str(shape[1]), "baseline_mm": repr(baseline_mm),
                         "focus_distance_m": "inf",
                         **{f"center_cam_{a}_m": repr(float(v)) for a, v in zip("xyz", centre_m)},
                         **{f"center_cam_r{a}_rad": repr(float(v)) for a, v in zip("xyz", rotation_rad)}}
    cfg["meta"] = {"disp_min": repr(d0), "disp_max": repr(d1), "frustum_disp_min": repr(d0),
                   "frustum_disp_max": repr(d1), "depth_map_scale": "1.0", "scene": scene, "category": "lps-calib",
                   "date": date, "version": version, "authors": "lps-calib", "contact": "-"}
    buf = io.StringIO()
    cfg.write(buf)
    path = folder / HCI_PARAMETERS
    write_text_atomic(path, buf.getvalue())
    return path


def read_hci(folder: Path | str) -> tuple[HciParameters, list[Path]]:
    """Read an HCI layout back: its parameters and its views row-major from the top-left, checked complete."""
    folder = Path(folder)
    text = read_file_limited(folder / HCI_PARAMETERS, what="HCI parameters file").decode("utf-8")
    cfg = configparser.ConfigParser()
    try:
        cfg.read_string(text)
        i, e = cfg["intrinsics"], cfg["extrinsics"]
        p = HciParameters(int(i["image_resolution_x_px"]), int(i["image_resolution_y_px"]), float(i["focal_length_mm"]),
                          float(i["sensor_size_mm"]), int(e["num_cams_x"]), int(e["num_cams_y"]), float(e["baseline_mm"]),
                          float(e["focus_distance_m"]), {s: dict(cfg[s]) for s in cfg.sections()})
        for key in ("disp_min", "disp_max", "scene"):
            cfg["meta"][key]
    except (configparser.Error, KeyError, ValueError) as exc:
        raise InputError(f"{folder / HCI_PARAMETERS}: not an HCI parameters file ({exc}); write it with lps lightfield")
    views = [folder / HCI_VIEW.format(k) for k in range(p.num_cams_x * p.num_cams_y)]
    missing = [v.name for v in views if not v.is_file()]
    if missing:
        raise InputError(f"{folder}: HCI view {missing[0]} is missing ({len(missing)} of {len(views)})")
    return p, views
