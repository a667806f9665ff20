"""The epipolar check of a rectified light field on the simulated scene's known points (issue 38).

A scene session rendered by the simulator knows its scene (``truth.scene``) and where the camera truly was
at every capture (``truth``, the rig's poses). Points on the scene's planes are projected through those
true poses and the true lens into every raw view (the exact positions a perfect matcher would find),
then through the same rectification as the images (the measured intrinsics and each view's measured
rotation: the exact inverse of the remap's map). Numbers:

- vertical disparity RMS before (raw image rows) and after rectification, over the points of every plane
  (a planar light field: within each row of views, and the horizontal one within each column);
- per plane parallel to the motion, the disparity against the measured and against the nominal positions
  (one slope, an intercept per point): residual RMS and the depth the slope implies, beside the true depth.

A real scene session (no truth) gets no numbers here, only the EPI pictures.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.geometry.camera_model import project
from lps_gui.core.intrinsics.crossval import unproject
from lps_gui.core.metrology.epipolar import disparity_fit, vertical_disparity_rms
from lps_gui.core.models.lightfield_views import VirtualCamera, grid_indices
from lps_gui.core.truth.scene import Scene, scene_points, visible_points
from lps_gui.core.truth.stage_errors import PlanarTruePose, TruePose
from lps_gui.io.session import Session
from lps_gui.pipeline.lightfield_views import MeasuredGeometry, SceneViews
from lps_gui.sim.rig import spec_from_truth
from lps_gui.sim.scene_session import session_scene


def true_camera_poses(scene: Session, views: SceneViews) -> tuple[Any, np.ndarray, np.ndarray] | None:
    """(rig, R (K, 3, 3), t (K, 3)) where the simulated camera truly was at each view, or None without truth."""
    truth = scene.truth or {}
    if "index" not in truth:
        return None
    rig = spec_from_truth(truth, scene.plan(), str(scene.folder / "session.json")).rig
    at = {int(i): k for k, i in enumerate(truth["index"])}
    pick = np.array([at[int(i)] for i in views.index])
    angles = np.asarray(truth["angles_urad"], float)[pick]
    if "plane_mm" in truth:
        pose: Any = PlanarTruePose(np.asarray(truth["plane_mm"], float)[pick],
                                   np.asarray(truth["normal_um"], float)[pick], angles)
    else:
        pose = TruePose(np.asarray(truth["axis_mm"], float)[pick], np.asarray(truth["straightness_um"], float)[pick],
                        angles)
    R, t = rig.camera_poses(pose)
    return rig, R, t


def point_tracks(scene_def: Scene, rig: Any, R: np.ndarray, t: np.ndarray, g: MeasuredGeometry, vc: VirtualCamera,
                 R_rect: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Raw (K, N, 2) and rectified (K, N, 2) positions of the scene's points (NaN where hidden or outside) and
    each point's plane (N,)."""
    P, owner = scene_points(scene_def)
    K = len(R)
    w, h = rig.intrinsics.image_size
    raw = np.full((K, len(P), 2), np.nan)
    rect = np.full((K, len(P), 2), np.nan)
    for k in range(K):
        C = -R[k].T @ t[k]
        xcam = P @ R[k].T + t[k]
        uv = project(xcam, rig.intrinsics).uv
        ok = visible_points(scene_def, C, P, owner) & (xcam[:, 2] > 0)
        ok &= (uv[:, 0] >= 0) & (uv[:, 0] <= w - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= h - 1)
        if not ok.any():
            continue
        raw[k, ok] = uv[ok]
        rays = unproject(uv[ok], g.intrinsics) @ R_rect[k].T  # the inverse of the images' remap, to ~1e-9 px
        r = (rays[:, :2] / rays[:, 2:]) @ vc.K[:2, :2].T + vc.K[:2, 2]
        inside = (r[:, 0] >= 0) & (r[:, 0] <= vc.image_size[0] - 1) & (r[:, 1] >= 0) & (r[:, 1] <= vc.image_size[1] - 1)
        sel = np.flatnonzero(ok)[inside]
        rect[k, sel] = r[inside]
    return raw, rect, owner


def epipolar_check(scene: Session, views: SceneViews, g: MeasuredGeometry, vc: VirtualCamera,
                   R_rect: np.ndarray) -> dict[str, Any] | None:
    """lightfield.json ``check``: the numbers above, or None for a real scene session."""
    scene_def = session_scene(scene)
    poses = true_camera_poses(scene, views) if scene_def is not None else None
    if poses is None:
        return None
    rig, R, t = poses
    raw, rect, owner = point_tracks(scene_def, rig, R, t, g, vc, R_rect)
    out: dict[str, Any] = {"basis": "known scene points through the true poses (simulated scene)",
                           "n_points": int(raw.shape[1])}
    if views.D == 2:  # a row of views (one Y) keeps a point's image row, a column (one X) its image column
        idx, _ = grid_indices(views.nominal_mm)
        for key, axis, group in (("vertical_disparity_rms_px", 1, idx[:, 1]), ("horizontal_disparity_rms_px", 0, idx[:, 0])):
            out[key] = {name: _pooled(track[..., axis], group) for name, track in (("before", raw), ("after", rect))}
        out["within"] = "views of one grid row (vertical) or one grid column (horizontal)"
        return out
    out["vertical_disparity_rms_px"] = {"before": vertical_disparity_rms(raw[..., 1]),
                                        "after": vertical_disparity_rms(rect[..., 1])}
    planes = []
    for j, plane in enumerate(scene_def.planes):
        if plane.depth_mm is None or not (owner == j).any():
            continue
        u = rect[:, owner == j, 0]
        fits = {name: disparity_fit(u, s) for name, s in (("measured", views.position_mm[:, 0]),
                                                           ("nominal", views.nominal_mm[:, 0]))}
        if fits["measured"].n_points == 0:
            continue
        planes.append({"plane": plane.name, "depth_mm": plane.depth_mm, "points": fits["measured"].n_points,
                       **{f"residual_rms_px_{n}": f.residual_rms_px for n, f in fits.items()},
                       **{f"depth_from_slope_mm_{n}": f.depth_mm(vc.focal_px) for n, f in fits.items()}})
    out["disparity_vs_position"] = planes
    return out


def _pooled(track: np.ndarray, group: np.ndarray) -> float:
    """RMS of a coordinate about its mean within each group of views, pooled over the groups."""
    sq, n = 0.0, 0
    for g in np.unique(group):
        t = track[group == g]
        keep = np.isfinite(t).sum(axis=0) >= 2
        if keep.any():
            d = t[:, keep] - np.nanmean(t[:, keep], axis=0)
            sq += float(np.nansum(d**2))
            n += int(np.isfinite(d).sum())
    return float(np.sqrt(sq / n)) if n else float("nan")
