"""results.json fields of the board-plane straightness and image rotation (SPEC 11).

``positions.csv`` ``straightness_um_1/_2`` carry the constant-orientation
figures (resolved to micrometres in the board plane); the per-view 6-DOF
pose's straightness stays in results.json as ``pose_straightness_um_1/_2``
for comparison. Figures carry their noise p-v and a ``resolved`` flag from
:mod:`lps_gui.core.metrology.resolution`, so report and GUI show only resolved ones.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.estimator.estimate_types import LpsEstimate
from lps_gui.core.metrology.resolution import max_abs_resolution, profile_span
from lps_gui.core.models.constant_orientation import rotation_read_as_shift
from lps_gui.io.results.document import json_floats


def _f(x: Any) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def position_columns(est: LpsEstimate) -> dict[str, list[Any]]:
    """The per-position straightness / image rotation entries of every view, as columns (K each)."""
    cols: dict[str, list[Any]] = {}
    bp, six = est.board_plane, est.six_dof
    if six is not None:
        for j in (0, 1):
            cols[f"pose_straightness_um_{j + 1}"] = json_floats(six.straightness_um[:, j])
            cols[f"pose_straightness_sigma_um_{j + 1}"] = json_floats(six.straightness_sigma_um[:, j])
    if bp is not None:
        for j in (0, 1):
            cols[f"straightness_um_{j + 1}"] = json_floats(bp.straightness_um[:, j])
            cols[f"straightness_sigma_um_{j + 1}"] = json_floats(bp.straightness_sigma_um[:, j])
        cols["image_rotation_urad"] = json_floats(bp.image_rotation_urad)
        cols["image_rotation_sigma_urad"] = json_floats(bp.image_rotation_sigma_urad)
    elif six is not None:  # per-view methods have no common orientation: the pose figures are all there is
        for j in (0, 1):
            cols[f"straightness_um_{j + 1}"] = cols[f"pose_straightness_um_{j + 1}"]
            cols[f"straightness_sigma_um_{j + 1}"] = cols[f"pose_straightness_sigma_um_{j + 1}"]
    return cols


def straightness_figures(target_mm: np.ndarray, est: LpsEstimate, valid: np.ndarray,
                         corners_px: np.ndarray | None = None) -> dict[str, Any]:
    """``figures`` entries: p-v of v1, v2 and image rotation over the targets, each with its noise p-v.

    The legacy keys (``straightness_um_max``, ``straightness_span_um``,
    ``straightness_sigma_um``) keep their meaning, now from the board-plane
    figures when the method has them. With the views' corners (``corners_px`` (K, N, 2)) a board-plane
    span also gets ``u_model_um``: the constant-orientation model overstates a carriage rotation's share
    of it (:func:`~lps_gui.core.models.constant_orientation.rotation_read_as_shift`); which share of the
    span is rotation is not known, so the whole measured span times that fraction is a standard
    uncertainty of the span (in its U, :func:`~lps_gui.core.metrology.uncertainty_budget.extreme_uncertainties`).
    """
    bp, six = est.board_plane, est.six_dof
    if bp is not None:
        values, sigma, basis = bp.straightness_um, bp.straightness_sigma_um, "board plane, constant orientation"
    elif six is not None:
        values, sigma, basis = six.straightness_um, six.straightness_sigma_um, "per-view 6-DOF poses"
    else:
        return {}
    ok = valid & np.all(np.isfinite(values), axis=1)
    if not ok.any():
        return {}
    order = 4 if bp is not None else 2  # the board plane's U names its systematic term: curvature is no noise
    spans = [profile_span(values[:, j], sigma[:, j], target_mm, ok, difference_order=order).to_dict("um")
             for j in (0, 1)]
    R = getattr(est.state, "R", None)
    if bp is not None and corners_px is not None and R is not None:
        share = rotation_read_as_shift(corners_px[ok], est.state.intrinsics, np.asarray(R) @ bp.frame[:, 1:])
        for span, f in zip(spans, share):
            span["u_model_um"] = None if span["measured_span_um"] is None else float(f) * span["measured_span_um"]
    out: dict[str, Any] = {
        "straightness_um_max": _f(np.nanmax(np.ptp(values[ok], axis=0))),
        "straightness_span_um": [_f(v) for v in np.ptp(values[ok], axis=0)],
        "straightness_sigma_um": _f(np.nanmax(np.nanmedian(sigma[ok], axis=0))),
        "straightness": {"basis": basis, "v1": spans[0], "v2": spans[1]},
    }
    if bp is not None:
        rot_ok = valid & np.isfinite(bp.image_rotation_urad)
        out["image_rotation"] = profile_span(bp.image_rotation_urad, bp.image_rotation_sigma_urad, target_mm,
                                             rot_ok).to_dict("urad")
    if six is not None:
        resolved = {}
        for j, name in enumerate(("roll", "pitch", "yaw")):
            r = max_abs_resolution(six.angles_urad[:, j], six.angles_sigma_urad[:, j], target_mm, valid)
            if r is not None:
                resolved[name] = {k: _f(v) if k != "resolved" else v for k, v in r.items()}
        out["angles_resolution"] = resolved
    return out
