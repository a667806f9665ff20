"""The simulator's truth of a planar (XY) session, compared through the one reduction.

Truth comes from session.json's ``truth`` (``index``, ``plane_mm`` (K, 2) true
stage-plane positions, ``board_plane_mm`` (K, 2) what a constant-orientation
model sees). Before :func:`lps_gui.sim.truth.reduce_truth` compares it, truth
is put in the estimate's frame convention (SPEC 10: origin at the reference
capture, +x along the fitted +X motion), by the same rule the estimator
applies to its own positions (:func:`core.planar_estimate.planar_truth_in_stage_frame`).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.planar_estimate import PlanarEstimate, PlanarObservations, planar_truth_in_stage_frame
from lps_gui.core.planar_figures import axis_geometry, planar_figures
from lps_gui.core.planar_estimate import affine_motion
from lps_gui.io.session import Session
from lps_gui.sim.truth import read_truth, reduce_truth, true_deviation_um


def planar_session_truth(session: Session) -> dict[str, Any] | None:
    """Arrays index (K,), plane_mm (K, 2), board_plane_mm (K, 2), or None for a real session."""
    meta = dict(session.meta.get("truth") or {})
    per_index = read_truth(session)  # a capture on the simulated gantry: newer than session.json while incomplete
    if per_index and all("plane_mm" in r for r in per_index.values()):
        rows = [per_index[i] for i in sorted(per_index)]
        meta.update(index=[r["index"] for r in rows], plane_mm=[r["plane_mm"] for r in rows],
                    board_plane_mm=[r["board_plane_mm"] for r in rows])
    if meta.get("plane_mm") is None:
        return None
    K = len(meta["plane_mm"])
    out: dict[str, Any] = {
        "index": np.array(meta.get("index", range(K)), dtype=int),
        "plane_mm": np.asarray(meta["plane_mm"], dtype=float).reshape(K, 2),
        "replaced_views": meta.get("replaced_views", []),
        "bumped_views": meta.get("bumped_views", []),
    }
    if meta.get("board_plane_mm") is not None:
        out["board_plane_mm"] = np.asarray(meta["board_plane_mm"], dtype=float).reshape(K, 2)
    squareness = ((meta.get("rig") or {}).get("stage_errors") or {}).get("squareness_urad")
    if squareness is not None:
        out["squareness_urad"] = float(squareness)
    return out


def _f(x: Any) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def planar_truth_comparison(obs: PlanarObservations, est: PlanarEstimate, truth: dict[str, Any],
                            positions: list[dict]) -> dict[str, Any]:
    """results.json ``truth_comparison`` of a planar session; also puts truth beside each position."""
    by_index = {int(i): k for k, i in enumerate(truth["index"])}
    rows = np.array([by_index.get(int(i), -1) for i in obs.index])
    have = rows >= 0
    ref = est.reference_view
    if not have[ref] or not have.all():
        return {"note": "truth does not cover every capture"}
    ok = est.used & have
    key = "board_plane_mm" if "board_plane_mm" in truth else "plane_mm"
    true_xy = planar_truth_in_stage_frame(truth[key][rows], obs.target_mm, obs.approach, ok, ref)
    pos = reduce_truth(est.state.xy, true_xy, ref, ok, est.sigma_xy_mm)
    sig = 1e3 * est.sigma_xy_mm[ok]
    true_geo = axis_geometry(affine_motion(true_xy, obs.target_mm, obs.approach, ok), np.zeros((4, 4)))
    geo = axis_geometry(est.fit.G, est.fit.cov_G)
    out: dict[str, Any] = {
        "reference": "board plane" if key == "board_plane_mm" else "carriage",
        "position_rms_error_um": pos.rms_um,
        "position_max_abs_error_um": pos.max_abs_um,
        "per_coordinate_rms_error_um": [_f(v) for v in np.sqrt(np.mean(pos.error_um[ok] ** 2, axis=0))],
        "mean_sigma_um": _f(np.sqrt(np.mean(sig**2))) if sig.size else None,
        "z_mean_square": pos.z_mean_square,
        "squareness_urad": true_geo.squareness_urad,
        "squareness_error_urad": geo.squareness_urad - true_geo.squareness_urad,
        "squareness_z": (geo.squareness_urad - true_geo.squareness_urad) / max(geo.squareness_sigma_urad, 1e-12),
        "scale_x_ppm": true_geo.scale_x_ppm,
        "scale_x_error_ppm": geo.scale_x_ppm - true_geo.scale_x_ppm,
        "scale_y_ppm": true_geo.scale_y_ppm,
        "scale_y_error_ppm": geo.scale_y_ppm - true_geo.scale_y_ppm,
        "injected_outliers": sorted(set(truth.get("replaced_views", [])) | set(truth.get("bumped_views", []))),
        "flagged_outliers": sorted(int(i) for i in obs.index[est.outlier]),
    }
    if "squareness_urad" in truth:
        out["model_squareness_urad"] = truth["squareness_urad"]
    true_dev = true_deviation_um(true_xy, obs.target_mm, ref)
    true_figs = planar_figures(obs.target_mm, obs.approach, obs.run, obs.direction, true_dev, np.ones_like(true_dev),
                               ok, np.eye(2), np.zeros((4, 4)))  # the same per-line reduction as the estimate's
    for axis in ("X", "Y"):
        out[f"straightness_{axis.lower()}_um"] = (true_figs.per_axis.get(axis) or {}).get("straightness_um_max")
    for k, row in enumerate(positions):
        row["truth_deviation_x_um"] = _f(true_dev[k, 0])
        row["truth_deviation_y_um"] = _f(true_dev[k, 1])
    return out
