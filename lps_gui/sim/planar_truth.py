"""The simulator's truth of a planar (XY) session, compared through the one reduction.

Truth comes from session.json's ``truth`` (``index``, ``plane_mm`` (K, 2) true
stage-plane positions, ``board_plane_mm`` (K, 2) what a constant-orientation
model sees). Before :func:`lps_gui.sim.truth.reduce_truth` compares it, truth
is put in the estimate's frame convention (SPEC 10: origin at the reference
capture, +x along the fitted +X motion), by the same rule the estimator
applies to its own positions (:func:`core.planar_model.planar_truth_in_stage_frame`).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.observations import Observations
from lps_gui.core.estimate_types import LpsEstimate
from lps_gui.core.planar_model import affine_motion, planar_truth_in_stage_frame
from lps_gui.core.planar_figures import axis_geometry, planar_figures
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
        if all("normal_um" in r and "angles_urad" in r for r in rows):
            meta.update(normal_um=[r["normal_um"] for r in rows], angles_urad=[r["angles_urad"] for r in rows])
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
    normal = _board_plane_normal_um(meta, out["plane_mm"], K)
    if normal is not None:
        out["board_plane_normal_um"] = normal
    return out


def _board_plane_normal_um(meta: dict[str, Any], plane_mm: np.ndarray, K: int) -> np.ndarray | None:
    """Where a constant-orientation model sees each true pose along the plane normal, at the board centre (um).

    The carriage's out-of-plane displacement plus what its rotation w does at
    the board: D = C + w x (X0 - C) (core.constant_orientation.board_plane_offsets,
    first order in w, no solver), projected on the stage's normal e_n.
    """
    rig, board = meta.get("rig") or {}, meta.get("board")
    if meta.get("normal_um") is None or meta.get("angles_urad") is None or not rig or not board:
        return None
    from lps_gui.core.constant_orientation import board_plane_offsets
    from lps_gui.io.board_file import board_from_dict

    E = np.asarray(rig["axes_board"], float)
    C0 = np.asarray(rig["C0_board"], float)
    normal = np.asarray(meta["normal_um"], float).reshape(K)
    C = C0[None, :] + plane_mm @ E[:, :2].T + 1e-3 * normal[:, None] * E[None, :, 2]
    w = 1e-6 * np.asarray(meta["angles_urad"], float).reshape(K, 3) @ E.T
    X0 = board_from_dict(board, "session.json truth").object_points().mean(axis=0)
    return 1e3 * (board_plane_offsets(C, w, X0) - C0[None, :]) @ E[:, 2]


def _f(x: Any) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def planar_truth_comparison(obs: Observations, est: LpsEstimate, truth: dict[str, Any],
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
    pos = reduce_truth(est.state.xy, true_xy, ref, ok, est.sigma_s_mm)
    sig = 1e3 * est.sigma_s_mm[ok]
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
    out.update(_out_of_plane_errors(obs, truth, rows, ok, positions))
    return out


def _out_of_plane_errors(obs: Observations, truth: dict[str, Any], rows: np.ndarray, ok: np.ndarray,
                         positions: list[dict]) -> dict[str, Any]:
    """The estimate's out-of-plane displacement against truth, both off their least-squares plane over ``ok``."""
    if "board_plane_normal_um" not in truth:
        return {}
    est_v = np.array([np.nan if r.get("out_of_plane_um") is None else r["out_of_plane_um"] for r in positions])
    est_s = np.array([np.nan if r.get("out_of_plane_sigma_um") is None else r["out_of_plane_sigma_um"]
                      for r in positions])
    keep = ok & np.isfinite(est_v) & np.isfinite(est_s)
    if keep.sum() < 4:
        return {}
    design = np.column_stack([np.ones(obs.K), obs.target_mm])
    true_v = truth["board_plane_normal_um"][rows]
    true_v = true_v - design @ np.linalg.lstsq(design[keep], true_v[keep], rcond=None)[0]
    err = est_v[keep] - true_v[keep]
    for k, row in enumerate(positions):
        row["truth_out_of_plane_um"] = _f(true_v[k])
    return {"out_of_plane_rms_error_um": _f(np.sqrt(np.mean(err**2))),
            "out_of_plane_z_mean_square": _f(np.mean((err / est_s[keep]) ** 2))}
