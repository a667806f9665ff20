"""`lps lightfield`: a scene session's views rectified to one virtual camera, with measured positions (SPEC 17).

Streamed: one view is read, rectified (undistorted and rotated by its measured rotation to the virtual
camera, :mod:`lps_gui.core.models.lightfield_views`), written and dropped before the next; only one image
row per view is kept for the epipolar-plane images. Written into ``out``: ``views/NNNNNN.png``,
``lightfield.json``, the HCI layout in ``hci/`` when the positions are a uniform grid within 2 sigma
(otherwise one line naming the largest deviation), COLMAP (``colmap/``) and nerfstudio (``nerfstudio/``)
models of the rectified set, and the epipolar check (``epi_before.png``, ``epi_after.png``, numbers in
lightfield.json ``check``, a report page ``report.pdf``).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import log_so3
from lps_gui.core.models.export_poses import world_to_camera
from lps_gui.core.models.lightfield_views import (
    GridCheck,
    VirtualCamera,
    grid_indices,
    rectifying_rotations,
    uniform_grid,
    view_rotations,
    virtual_camera,
)
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.export_files import write_colmap, write_nerfstudio
from lps_gui.io.image_file import read_image
from lps_gui.io.lightfield_files import HCI_VIEW, write_hci_parameters, write_lightfield_json, write_png
from lps_gui.io.scene_link import linked_measurement
from lps_gui.io.session import Session
from lps_gui.io.session_paths import resolve_in_session
from lps_gui.pipeline.compensate import session_results
from lps_gui.pipeline.lightfield_views import MeasuredGeometry, SceneViews, measured_geometry, scene_views

VIEWS_DIR = "views"
EPI_MIN_HEIGHT = 240  # rows of an EPI picture: each view's row repeated to at least this height


@dataclass
class LightFieldResult:
    out: Path
    n_views: int = 0
    files: list[Path] = field(default_factory=list)
    hci: Path | None = None
    refusal: str | None = None
    grid: GridCheck | None = None
    check: dict[str, Any] | None = None
    epi_row: int = 0


def virtual_intrinsics(vc: VirtualCamera) -> CameraIntrinsics:
    """The virtual camera as intrinsics without distortion (what the rectified views are seen through)."""
    K = vc.K
    return CameraIntrinsics.from_values(vc.image_size, K[0, 0], K[1, 1], K[0, 2], K[1, 2])


def hci_refusal(grid: GridCheck, views: SceneViews) -> str | None:
    """None when the HCI layout may be written; else one line naming the largest deviation and what to do."""
    axis = "XY"[grid.worst_axis]
    if not grid.complete:
        return (f"HCI layout not written: the views are not a complete grid ({views.position_mm.shape[0]} views for "
                f"{' x '.join(map(str, grid.shape))} nodes); capture every stop of the grid once")
    if views.D == 2 and abs(grid.spacing_mm[0] - grid.spacing_mm[1]) > 1e-3 * 2 * float(np.max(views.sigma_um)):
        return (f"HCI layout not written: one baseline for both axes, but X steps {grid.spacing_mm[0]:.4f} mm and Y "
                f"{grid.spacing_mm[1]:.4f} mm; capture a square grid")
    if grid.uniform:
        return None
    k = grid.worst
    todo = ("capture the scene through the measurement's compensation table (lps compensate, then lps capture "
            "--scene ... --compensation FILE)") if views.D == 1 else \
        "a planar stage has no compensation here: use lightfield.json's measured positions instead"
    return (f"HCI layout not written: view {int(views.index[k])} ({views.files[k]}) is "
            f"{grid.residual_um[k, grid.worst_axis]:+.1f} um off a uniform grid along {axis}, "
            f"{grid.z[k, grid.worst_axis]:.1f} sigma (sigma {views.sigma_um[k, grid.worst_axis]:.1f} um, limit 2); {todo}")


def hci_order(views: SceneViews, g: MeasuredGeometry, vc: VirtualCamera) -> np.ndarray:
    """View numbers in HCI order: row-major from the top-left view (rows down the virtual y, columns along x)."""
    idx, shape = grid_indices(views.nominal_mm)
    col = idx[:, 0] if float(g.axes[:, 0] @ vc.R[0]) > 0 else shape[0] - 1 - idx[:, 0]
    if views.D == 1:
        return np.argsort(col, kind="stable")
    row = idx[:, 1] if float(g.axes[:, 1] @ vc.R[1]) > 0 else shape[1] - 1 - idx[:, 1]
    return np.lexsort((col, row))


class EpiRows:
    """One image row of every view, before (raw) and after rectification: the epipolar-plane images."""

    def __init__(self, K: int, width: int, row: int) -> None:
        self.row = row
        self.before = np.zeros((K, width), np.uint8)
        self.after = np.zeros((K, width), np.uint8)

    def add(self, k: int, raw: np.ndarray, rectified: np.ndarray) -> None:
        self.before[k] = raw[self.row]
        self.after[k] = rectified[self.row]

    def pictures(self, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rep = max(1, int(np.ceil(EPI_MIN_HEIGHT / len(order))))
        return np.repeat(self.before[order], rep, axis=0), np.repeat(self.after[order], rep, axis=0)


def make_lightfield(scene_dir: Path | str, out: Path | str, measurement: Path | str | None = None,
                    epi_row: int | None = None, progress: ProgressFn = no_progress,
                    cancel: CancelToken | None = None) -> LightFieldResult:
    """Rectify every view of ``scene_dir`` into ``out`` and write lightfield.json, HCI, COLMAP, nerfstudio, EPIs."""
    scene = Session.open(scene_dir)
    measured, link = linked_measurement(scene, measurement)
    results = session_results(measured.folder, "lightfield")
    g = measured_geometry(results, measured)
    views = scene_views(scene, results, g)
    vc = virtual_camera(g.R, g.axes, g.intrinsics)
    R_rect = rectifying_rotations(vc, view_rotations(g.R, views.tilt_rad, views.image_rotation_rad))
    grid = uniform_grid(views.position_mm, views.nominal_mm, views.sigma_um)
    res = LightFieldResult(Path(out), grid=grid, refusal=hci_refusal(grid, views))
    out = Path(out)
    (out / VIEWS_DIR).mkdir(parents=True, exist_ok=True)
    w, h = vc.image_size
    K = len(views.files)
    row_views = np.arange(K) if views.D == 1 else np.flatnonzero(grid_indices(views.nominal_mm)[0][:, 1] == 0)
    epi = EpiRows(len(row_views), w, int(h // 2 if epi_row is None else epi_row))
    if not 0 <= epi.row < h:
        raise InputError(f"--epi-row {epi.row}: outside the image (0..{h - 1})")
    names = []
    intr = g.intrinsics
    for k in range(K):
        if cancel is not None:
            cancel.check("light field")
        raw = read_image(resolve_in_session(scene.folder, views.files[k], f"{scene.folder}/captures.jsonl"),
                         cv2.IMREAD_UNCHANGED)
        m1, m2 = cv2.initUndistortRectifyMap(intr.camera_matrix, intr.dist, R_rect[k], vc.K, (w, h), cv2.CV_32FC1)
        rect = cv2.remap(raw, m1, m2, cv2.INTER_CUBIC, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        name = f"{VIEWS_DIR}/{int(views.index[k]):06d}.png"
        write_png(out / name, rect)
        names.append(name)
        if k in row_views:
            epi.add(int(np.searchsorted(row_views, k)), raw if raw.ndim == 2 else raw[..., 0],
                    rect if rect.ndim == 2 else rect[..., 0])
        progress(k + 1, K, f"view {k + 1}/{K}")
    res.n_views, res.epi_row = K, epi.row
    res.files = [out / n for n in names]
    C = views.centres(g)
    vintr = virtual_intrinsics(vc)
    res.files += write_colmap(out / "colmap", vintr, vc.R, world_to_camera(vc.R, C), names,
                              measured.board().object_points() if measured.targets() is None else np.zeros((0, 3)))
    res.files.append(write_nerfstudio(out / "nerfstudio", vintr, vc.R, C, names, ".."))
    order = hci_order(views, g, vc)
    if res.refusal is None:
        res.hci = _write_hci(out / "hci", views, grid, vc, C, order, names, out, scene.folder.name)
        res.files.append(res.hci)
    before, after = epi.pictures(hci_order(_subset(views, row_views), g, vc))  # views left to right, top down
    for name, pic in (("epi_before.png", before), ("epi_after.png", after)):
        write_png(out / name, pic)
        res.files.append(out / name)
    from lps_gui.pipeline.lightfield_check import epipolar_check

    res.check = epipolar_check(scene, views, g, vc, R_rect)
    doc = {
        "measurement_session": link,
        "scene_session": str(scene.folder.resolve()),
        "virtual_camera": {"image_size": list(vc.image_size), "camera_matrix": vc.K.tolist()},
        "R_cam_board": vc.R.tolist(),
        "axes": ["X", "Y"][: views.D],
        "rotation_source": views.rotation_source,
        "uniform": {"grid": list(grid.shape), "spacing_mm": grid.spacing_mm.tolist(), "max_sigmas":
                    float(grid.z.max()), "hci": res.refusal is None, **({"refusal": res.refusal} if res.refusal else {})},
        "epi_row": epi.row,
        "views": [{"file": names[k], "index": int(views.index[k]), "source": views.files[k],
                   "position_mm": views.position_mm[k].tolist(), "sigma_um": views.sigma_um[k].tolist(),
                   "nominal_mm": views.nominal_mm[k].tolist(),
                   **({"commanded_mm": views.commanded_mm[k].tolist()}
                      if not np.allclose(views.commanded_mm[k], views.nominal_mm[k]) else {}),
                   "centre_mm": C[k].tolist(), "rectifying_rvec_rad": log_so3(R_rect[k]).tolist()}
                  for k in range(K)],
        **({"check": res.check} if res.check else {}),
    }
    res.files.insert(0, write_lightfield_json(out, doc))
    from lps_gui.report.registry import folder_section

    section = folder_section("lightfield")  # its PDF, as the registry names it
    section.write_report(doc, before, after, out / section.report_file)
    res.files.append(out / section.report_file)
    return res


def _subset(views: SceneViews, keep: np.ndarray) -> SceneViews:
    from dataclasses import replace

    return replace(views, index=views.index[keep], files=[views.files[k] for k in keep],
                   nominal_mm=views.nominal_mm[keep], commanded_mm=views.commanded_mm[keep],
                   position_mm=views.position_mm[keep], sigma_um=views.sigma_um[keep], tilt_rad=views.tilt_rad[keep],
                   image_rotation_rad=views.image_rotation_rad[keep])


def _write_hci(folder: Path, views: SceneViews, grid: GridCheck, vc: VirtualCamera, C: np.ndarray,
               order: np.ndarray, names: list[str], out: Path, scene_name: str) -> Path:
    """The HCI layout: input_CamNNN.png (hard links to the rectified views, copies where links fail), parameters."""
    folder.mkdir(parents=True, exist_ok=True)
    for n, k in enumerate(order):
        target = folder / HCI_VIEW.format(n)
        if target.exists() or target.is_symlink():
            target.unlink()
        try:
            os.link(out / names[k], target)
        except OSError:
            write_png(target, read_image(out / names[k], cv2.IMREAD_UNCHANGED))
    shape = (grid.shape[0], grid.shape[1] if views.D == 2 else 1)
    from lps_gui import __version__

    return write_hci_parameters(folder, image_size=vc.image_size, focal_px=vc.focal_px, pixel_mm=1e-3, shape=shape,
                                baseline_mm=float(abs(grid.spacing_mm[0])), centre_m=1e-3 * C.mean(axis=0),
                                rotation_rad=log_so3(vc.R.T), scene=scene_name, date=time.strftime("%Y-%m-%d"),
                                version=__version__, disparity=None)


def check_lines(check: dict[str, Any] | None) -> list[str]:
    """The epipolar check's numbers as printed lines: :func:`lps_gui.report.pages.lightfield.check_lines`."""
    from lps_gui.report.pages.lightfield import check_lines as lines

    return lines(check)
