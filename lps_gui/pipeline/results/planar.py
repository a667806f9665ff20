"""The results.json document of a two-axis (planar) estimate (SPEC 10).

:func:`lps_gui.pipeline.estimate.estimate_session` is the way here for every
D; this module only assembles the planar parts: ``axes: ["X", "Y"]``, the
planar positions table, ``figures.planar`` and the summary rows (:func:`summary_csv_rows`, made by the caller
from the finished document). The environment and the uncertainty budget are added by the caller as for a line.
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

from lps_gui import __version__
from lps_gui.core.estimator.estimate_types import LpsEstimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
from lps_gui.core.geometry.rotation import log_so3
from lps_gui.core.metrology.planar_figures import node_errors, planar_figures
from lps_gui.core.metrology.planar_flatness import out_of_plane
from lps_gui.io.board_file import board_to_dict
from lps_gui.io.intrinsics_file import intrinsics_to_dict
from lps_gui.io.results.document import FORMAT
from lps_gui.io.results.sections import Figures, Flag, Parameters, TruthComparison
from lps_gui.pipeline.results.parts import AxisResults
from lps_gui.pipeline.session_checks import session_inputs
from lps_gui.pipeline.session_input import SessionInput
from lps_gui.sim.truth import plane_true_deviation_um, truth_comparison


def _f(x: Any) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def build_planar_results(session: SessionInput, obs: Observations, est: LpsEstimate, intrinsics_source: str
                         ) -> AxisResults:
    """The results.json document of a planar session (SPEC 10; schema in docs/ARCHITECTURE.md) and its values."""
    dev = est.deviation_um(obs.target_mm)
    sig = 1e3 * est.sigma_s_mm
    sig_total = 1e3 * est.sigma_total_mm
    ref_target = obs.target_mm[est.reference_view]
    oop = None
    if est.method == "joint" and obs.mounted is None:  # the displacement along the plane normal at the board plane
        # (core/metrology/planar_flatness; of one board: a constellation has no one board plane)
        oop = out_of_plane(est.state, obs.board.object_points(), obs.corners_px, obs.mask() & est.usable[:, None],
                           obs.target_mm, est.used)
    positions = []
    for i in range(obs.K):
        ok = bool(est.usable[i])
        positions.append({
            "index": int(obs.index[i]), "run": int(obs.run[i]), "direction": "+" if obs.direction[i] > 0 else "-",
            "target_x_mm": float(obs.target_mm[i, 0]), "target_y_mm": float(obs.target_mm[i, 1]),
            "measured_x_mm": _f(est.state.xy[i, 0] + ref_target[0]) if ok else None,
            "measured_y_mm": _f(est.state.xy[i, 1] + ref_target[1]) if ok else None,
            "deviation_x_um": _f(dev[i, 0]) if ok else None, "deviation_y_um": _f(dev[i, 1]) if ok else None,
            "sigma_x_um": _f(sig[i, 0]) if est.used[i] else None, "sigma_y_um": _f(sig[i, 1]) if est.used[i] else None,
            "sigma_total_x_um": _f(sig_total[i, 0]) if est.used[i] else None,
            "sigma_total_y_um": _f(sig_total[i, 1]) if est.used[i] else None,
            "rms_px": _f(est.rms_px[i]), "n_corners": int(est.n_corners[i]), "outlier": bool(est.outlier[i]),
            "outlier_reason": est.outlier_reason[i] or ("board not found" if not ok else ""),
            "used": bool(est.used[i]), "approach": [int(v) for v in obs.approach[i]], "file": obs.names[i],
            **({} if oop is None else {"out_of_plane_um": _f(oop.normal_um[i]),
                                       "out_of_plane_sigma_um": _f(oop.sigma_um[i])}),
        })
    valid = est.used & np.all(np.isfinite(dev), axis=1)
    sig_fig = np.where(sig > 0, sig, np.nanmedian(sig[valid & (sig[:, 0] > 0)], axis=0) if valid.any() else 1.0)
    figs = planar_figures(obs.target_mm, obs.approach, obs.run, obs.direction, dev, sig_fig, valid,
                          est.fit.G, est.fit.cov_G, None if oop is None else oop.normal_um,
                          None if oop is None else oop.sigma_um)
    truth, tc, nodes = session.truth, None, figs.nodes
    if truth is not None:
        section, positions = truth_comparison(  # new rows, truth beside each position
            obs, est, truth, positions, None if oop is None else (oop.normal_um, oop.sigma_um))
        tc = TruthComparison.of(**section).to_dict()
        nodes = _nodes_with_truth(nodes, obs, plane_true_deviation_um(obs, est, truth), valid)
    planar = {**figs.geometry.to_dict(), "per_axis": figs.per_axis, "lines": [ln.to_dict() for ln in figs.lines],
              "nodes": nodes, "notes": figs.notes, "motion_matrix": est.fit.G.tolist()}
    figures = Figures.of(planar=planar).to_dict()  # written through the readers' definition
    st = est.state
    parameters = {
        "R_cam_board": st.R.tolist(), "rvec_rad": log_so3(st.R).tolist(), "l0_cam_mm": st.l0.tolist(),
        "n_x_cam": st.P[:, 0].tolist(), "n_y_cam": st.P[:, 1].tolist(),
        "u_x_board": st.motion_axes_board()[:, 0].tolist(), "u_y_board": st.motion_axes_board()[:, 1].tolist(),
        "sigma_px": est.sigma_px, "rms_px": _f(np.sqrt(np.nanmean(est.rms_px[est.used] ** 2))),
        "n_views": obs.K, "n_used": int(est.used.sum()), "n_outliers": int(est.outlier.sum()),
        "n_observations": est.n_observations, "dof": est.dof, "iterations": est.iterations,
        "converged": est.converged, "reference_index": int(obs.index[est.reference_view]),
    }
    if est.options.self_calibrate:
        parameters["intrinsics_estimated"] = dict(zip(INTRINSIC_NAMES, st.intrinsics.vector().tolist()))
    parameters = Parameters.of(**parameters).to_dict()
    inputs = session_inputs(session, intrinsics_source, {session.corners_path.name: obs.source_sha256})
    board, flags = board_to_dict(obs.board), [Flag.of(**f).to_dict() for f in est.flags]
    results: dict[str, Any] = {
        "format": FORMAT, "software": {"name": "lps-calib", "version": __version__},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "method": est.method, "axes": ["X", "Y"],
        "settings": est.options.to_dict(), "inputs": inputs, "board": board,
        "intrinsics": intrinsics_to_dict(obs.intrinsics),
        "session_meta": {k: session.meta.get(k) for k in ("camera", "stage", "plan", "stage_spec", "created")
                         if k in session.meta},
        "parameters": parameters, "positions": positions, "figures": figures,
        "flags": flags, "timings_s": dict(est.timings_s), **({} if tc is None else {"truth_comparison": tc}),
        "summary": [],  # in its place: summary.csv's rows are made from the finished document
    }
    return AxisResults(results, parameters, board, positions, figures, flags, tc)


def _nodes_with_truth(nodes: list[dict[str, Any]], obs: Observations, true_dev: np.ndarray,
                      valid: np.ndarray) -> list[dict[str, Any]]:
    """New nodes with the simulator's mean error vector at each, beside the measured one (for the error map);
    ``true_dev`` (K, 2) is the true deviation of every capture, NaN where not compared."""
    ok = valid & np.all(np.isfinite(true_dev), axis=1)
    truth_nodes = node_errors(obs.target_mm, obs.direction, true_dev, np.ones_like(true_dev), ok)
    return [{**node, "truth_error_um": t.get("error_um")} for node, t in zip(nodes, truth_nodes)]


def summary_csv_rows(results: dict[str, Any]) -> list[tuple[str, Any, str]]:
    """(name, value, unit) rows for summary.csv of a planar session."""
    p = results["parameters"]
    pl = results["figures"]["planar"]
    rows: list[tuple[str, Any, str]] = [
        ("method", results["method"], ""), ("axes", "X,Y", ""), ("views", p["n_views"], ""),
        ("views_used", p["n_used"], ""), ("outlier_views", p["n_outliers"], ""),
        ("corner_noise_sigma", p["sigma_px"], "px"), ("rms_reprojection", p["rms_px"], "px"),
        ("squareness", pl["squareness_urad"], "urad"), ("squareness_sigma", pl["squareness_sigma_urad"], "urad"),
        ("squareness_um_per_m", pl["squareness_um_per_m"], "um/m"),
        ("scale_x", pl["scale_x_ppm"], "ppm"), ("scale_x_sigma", pl["scale_x_sigma_ppm"], "ppm"),
        ("scale_y", pl["scale_y_ppm"], "ppm"), ("scale_y_sigma", pl["scale_y_sigma_ppm"], "ppm"),
    ]
    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl["per_axis"].get(axis)
        if not a:
            continue
        st = a.get("straightness") or {}
        resolved = st.get("resolved", True)  # an unresolved span keeps its row, empty (no finding)
        rows.append((f"straightness_{axis.lower()}_along_{other.lower()}_max", a["straightness_um_max"] if resolved else None,
                     "um"))
        if st:
            rows.append((f"straightness_{axis.lower()}_along_{other.lower()}_noise_span", st.get("noise_span_um"), "um"))
        oop = a.get("out_of_plane")
        if oop:
            rows.append((f"out_of_plane_straightness_{axis.lower()}_max", oop["span_um"] if oop.get("resolved") else None,
                         "um"))
            rows.append((f"out_of_plane_straightness_{axis.lower()}_noise_span", oop.get("noise_span_um"), "um"))
        iso = (a.get("iso230_2") or {}).get("iso230_2") or {}
        for key in ("A_um", "R_um", "E_um", "B_um"):
            if iso.get(key) is not None:
                rows.append((f"iso230_2_{axis.lower()}_{key[:-3]}", iso[key], "um"))
    tc = results.get("truth_comparison") or {}
    if tc.get("position_rms_error_um") is not None:
        rows.append(("truth_position_rms_error", tc["position_rms_error_um"], "um"))
        rows.append(("truth_position_max_abs_error", tc["position_max_abs_error_um"], "um"))
    rows.append(("software_version", results["software"]["version"], ""))
    return rows
