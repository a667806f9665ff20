"""Estimate a session: read its files, run the estimator, write results (SPEC 7).

Reads session.json, captures.jsonl and corners.vnl, runs
:func:`lps_gui.core.estimate.estimate`, adds the accuracy figures and, for a
simulated session, the error against truth, and writes results.json,
positions.csv and summary.csv. Everything is computed before anything is
written, so a failure leaves the session as it was.
"""
from __future__ import annotations

import time
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui import __version__
from lps_gui.core.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.estimate import EstimateOptions, LpsEstimate, estimate
from lps_gui.core.hybrid import HybridOptions
from lps_gui.core.observations import Observations
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.rotation import log_so3
from lps_gui.errors import InputError
from lps_gui.io.atomic import sha256_file
from lps_gui.io.board_file import board_to_dict
from lps_gui.io.corners_vnl import read_corners_vnl
from lps_gui.io.intrinsics_file import intrinsics_to_dict, read_intrinsics
from lps_gui.io.results_file import FORMAT, write_results
from lps_gui.io.session import SESSION_FILE, Session
from lps_gui.io.session_lock import SessionLock
from lps_gui.pipeline.session_checks import check_corners_current, check_view_geometry
from lps_gui.pipeline.truth import session_truth

HYBRID_KEYS = {"grid_window_mm": "window_mm", "grid_resolution_mm": "resolution_mm", "grid_points": "grid_points",
               "threshold_px": "threshold_rms_px", "max_rounds": "max_rounds"}


def make_options(method: str = "joint", options: dict[str, Any] | EstimateOptions | None = None) -> EstimateOptions:
    """EstimateOptions from a plain dict (GUI, CLI) with the hybrid's keys flattened."""
    if isinstance(options, EstimateOptions):
        return replace(options, method=method)
    opts = dict(options or {})
    given = {k: opts.pop(k) for k in list(opts) if k in HYBRID_KEYS}
    hybrid = {HYBRID_KEYS[k]: v for k, v in given.items() if v is not None}
    unknown = set(opts) - set(EstimateOptions.__dataclass_fields__)
    if unknown:
        raise InputError(f"unknown estimation option(s): {', '.join(sorted(unknown))}")
    return EstimateOptions(method=method, hybrid=HybridOptions(**hybrid), **opts)


def observations_from_session(session: Session, intrinsics: CameraIntrinsics | None = None) -> Observations:
    """Match every line of captures.jsonl to its corners in corners.vnl."""
    board = session.board()
    intr = intrinsics or session.intrinsics()
    records = session.records()
    if not records:
        raise InputError(f"{session.captures_path}: no captures listed; capture or simulate a session first")
    table = read_corners_vnl(session.corners_path, board.n_corners)
    check_corners_current(session, table, records)
    rows = table.index()
    missing = [r.file for r in records if r.file not in rows]
    if missing:
        raise InputError(
            f"{session.corners_path}: {len(missing)} captured image(s) have no corners (first: {missing[0]}); run `lps detect {session.folder}`"
        )
    corners = table.corners_px[[rows[r.file] for r in records]]
    check_view_geometry(corners, [r.file for r in records], session.corners_path)
    return Observations(
        board=board,
        intrinsics=intr,
        corners_px=corners,
        target_mm=[r.target_mm for r in records],
        direction=[1.0 if r.direction == "+" else -1.0 for r in records],
        run=[r.run for r in records],
        index=[r.index for r in records],
        names=[r.file for r in records],
        source=str(session.corners_path),
    )


def estimate_session(
    session_dir: Path | str,
    method: str = "joint",
    options: dict[str, Any] | EstimateOptions | None = None,
    intrinsics_path: Path | str | None = None,
    out_dir: Path | str | None = None,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> dict[str, Any]:
    """Estimate a session folder and write results.json, positions.csv, summary.csv.

    Returns the results.json content.
    """
    t0 = time.perf_counter()
    session = Session.open(session_dir)
    opt = make_options(method, options)
    intr = read_intrinsics(intrinsics_path) if intrinsics_path else None
    obs = observations_from_session(session, intr)
    est = estimate(obs, opt, progress, cancel)
    results = build_results(session, obs, est, intrinsics_source=str(intrinsics_path or "session.json"))
    results["timings_s"]["pipeline_total"] = time.perf_counter() - t0
    if cancel is not None:
        cancel.check("estimation")
    with SessionLock(session.folder) if not out_dir else nullcontext():
        write_results(Path(out_dir) if out_dir else session.folder, results)
    return results


# ----------------------------------------------------------------------------- results

def _f(x: Any) -> float | None:
    """JSON float: NaN and inf become null."""
    x = float(x)
    return x if np.isfinite(x) else None


def build_results(session: Session, obs: Observations, est: LpsEstimate, intrinsics_source: str) -> dict[str, Any]:
    """The results.json document (schema in docs/ARCHITECTURE.md)."""
    from lps_gui.core.iso230 import figures_for_session

    dev_um = est.deviation_um(obs.target_mm)
    six = est.six_dof
    positions = []
    for i in range(obs.K):
        row: dict[str, Any] = {
            "index": int(obs.index[i]),
            "run": int(obs.run[i]),
            "direction": "+" if obs.direction[i] > 0 else "-",
            "target_mm": float(obs.target_mm[i]),
            "measured_mm": _f(est.state.s[i] + obs.target_mm[est.reference_view]) if est.usable[i] else None,
            "deviation_um": _f(dev_um[i]) if est.usable[i] else None,
            "sigma_um": _f(1e3 * est.sigma_s_mm[i]),
            "sigma_total_um": _f(1e3 * est.sigma_total_mm[i]),
            "step_sigma_um": _f(1e3 * est.step_sigma_mm[i]),
            "rms_px": _f(est.rms_px[i]),
            "n_corners": int(est.n_corners[i]),
            "outlier": bool(est.outlier[i]),
            "outlier_reason": est.outlier_reason[i] or ("board not found" if not est.usable[i] else ""),
            "used": bool(est.used[i]),
            "file": obs.names[i],
        }
        if six is not None:
            for j, key in enumerate(("straightness_um_1", "straightness_um_2")):
                row[key] = _f(six.straightness_um[i, j])
                row[key.replace("um_", "sigma_um_")] = _f(six.straightness_sigma_um[i, j])
            for j, key in enumerate(("roll", "pitch", "yaw")):
                row[f"{key}_urad"] = _f(six.angles_urad[i, j])
                row[f"{key}_sigma_urad"] = _f(six.angles_sigma_urad[i, j])
        positions.append(row)

    valid = est.used & np.isfinite(dev_um)
    # the reference capture has sigma 0 by definition of the gauge; weight it like a typical one
    sigma_um = 1e3 * est.sigma_s_mm
    positive = valid & (sigma_um > 0)
    sigma_um = np.where(valid & ~(sigma_um > 0), np.median(sigma_um[positive]) if positive.any() else 1.0, sigma_um)
    figures = figures_for_session(obs.target_mm, obs.direction, obs.run, dev_um, valid=valid, sigma_um=sigma_um)
    single = figures.get("single_run")
    if single is not None and valid.sum() >= 3:
        single.update(scale_with_uncertainty(obs, est, valid))
    if six is not None and valid.any():
        figures["straightness_um_max"] = _f(np.nanmax(np.ptp(six.straightness_um[valid], axis=0)))
        figures["straightness_span_um"] = [_f(v) for v in np.ptp(six.straightness_um[valid], axis=0)]
        figures["straightness_sigma_um"] = _f(np.nanmax(np.nanmedian(six.straightness_sigma_um[valid], axis=0)))
        figures["angles_span_urad"] = dict(zip(("roll", "pitch", "yaw"), (_f(v) for v in np.ptp(six.angles_urad[valid], axis=0))))

    line = est.state.line()
    parameters = {
        "R_cam_board": line.R_cam_board.tolist(),
        "rvec_rad": log_so3(line.R_cam_board).tolist(),
        "l0_cam_mm": line.l0_cam.tolist(),
        "n_cam": line.n_cam.tolist(),
        "u_board": line.u_board.tolist(),
        **est.parameter_sigmas,
        "sigma_px": est.sigma_px,
        "rms_px": _f(np.sqrt(np.nanmean(est.rms_px[est.used] ** 2))),
        "n_views": obs.K,
        "n_used": int(est.used.sum()),
        "n_outliers": int(est.outlier.sum()),
        "n_observations": est.n_observations,
        "dof": est.dof,
        "iterations": est.iterations,
        "converged": est.converged,
        "reference_index": int(obs.index[est.reference_view]),
    }
    if est.options.self_calibrate:
        parameters["intrinsics_estimated"] = dict(zip(INTRINSIC_NAMES, est.state.intrinsics.vector().tolist()))

    inputs = {"session": str(session.folder), "intrinsics_source": intrinsics_source, "sha256": {}}
    for name in (SESSION_FILE, session.captures_path.name, session.corners_path.name):
        path = session.folder / name
        if path.exists():
            inputs["sha256"][name] = sha256_file(path)

    results: dict[str, Any] = {
        "format": FORMAT,
        "software": {"name": "lps-calib", "version": __version__},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "method": est.method,
        "settings": est.options.to_dict(),
        "inputs": inputs,
        "board": board_to_dict(obs.board),
        "intrinsics": intrinsics_to_dict(obs.intrinsics),
        "session_meta": {k: session.meta.get(k) for k in ("camera", "stage", "plan", "stage_spec", "created") if k in session.meta},
        "parameters": parameters,
        "positions": positions,
        "figures": figures,
        "flags": est.flags,
        "timings_s": dict(est.timings_s),
    }
    truth = session_truth(session)
    if truth is not None:
        results["truth_comparison"] = truth_comparison(obs, est, truth, positions)
    results["summary"] = summary_rows(results)
    return results


def scale_with_uncertainty(obs: Observations, est: LpsEstimate, valid: np.ndarray) -> dict[str, Any]:
    """Linear scale error (ppm) and its sigma from the full covariance.

    Least-squares slope of the deviations against the target with one offset
    per run and direction (backlash is not scale). Its sigma counts the
    correlations between positions (from the board distance and direction)
    and, in total, the intrinsics: a focal-length error is a pure scale error.
    """
    groups = obs.run * 2 + (obs.direction > 0)
    cols = [obs.target_mm * valid] + [((groups == g) & valid).astype(float) for g in np.unique(groups[valid])]
    design = np.stack(cols, axis=1)[valid]
    slope_row = np.zeros(obs.K)
    slope_row[valid] = np.linalg.pinv(design)[0]  # slope = slope_row @ deviation
    dev_mm = est.state.s - (obs.target_mm - obs.target_mm[est.reference_view])
    sigma_noise, sigma_total = est.linear_functional_sigma(slope_row)
    return {
        "scale_ppm": _f(1e6 * slope_row @ np.where(valid, dev_mm, 0.0)),
        "scale_sigma_ppm": _f(1e6 * sigma_noise),
        "scale_sigma_total_ppm": _f(1e6 * sigma_total),
    }


def truth_comparison(obs: Observations, est: LpsEstimate, truth: dict[str, np.ndarray], positions: list[dict]) -> dict[str, Any]:
    """Errors against the simulator's truth; also puts truth beside each position for plots."""
    by_index = {int(i): k for k, i in enumerate(truth["index"])}
    rows = np.array([by_index.get(int(i), -1) for i in obs.index])
    have = rows >= 0
    if not have[est.reference_view]:
        return {"note": "truth does not cover the reference capture"}
    axis = np.where(have, truth["axis_mm"][rows], np.nan)
    s_true = axis - axis[est.reference_view]
    err_um = 1e3 * (est.state.s - s_true)
    ok = est.used & have
    z = err_um[ok] / np.maximum(1e3 * est.sigma_s_mm[ok], 1e-12)
    z = z[np.isfinite(z) & (np.arange(obs.K)[ok] != est.reference_view)]
    nominal = obs.target_mm - obs.target_mm[est.reference_view]
    true_dev = 1e3 * (s_true - nominal)
    # the estimate's straightness is relative to a least-squares line and its
    # angles to the common rotation: put truth in the same reference
    straight = _detrended(truth.get("straightness_um"), rows, have, ok, obs.target_mm)
    angles = truth.get("angles_urad")
    if angles is not None:
        angles = angles - np.mean(angles[rows[ok]], axis=0)
    for k, row in enumerate(positions):
        if not have[k]:
            continue
        row["truth_deviation_um"] = _f(true_dev[k])
        if straight is not None:
            row["truth_straightness_um_1"] = _f(straight[k, 0])
            row["truth_straightness_um_2"] = _f(straight[k, 1])
        if angles is not None:
            for j, key in enumerate(("roll", "pitch", "yaw")):
                row[f"truth_{key}_urad"] = _f(angles[rows[k], j])
    injected = sorted(set(truth.get("replaced_views", [])) | set(truth.get("bumped_views", [])))
    flagged = sorted(int(i) for i in obs.index[est.outlier])
    out = {
        "position_rms_error_um": _f(np.sqrt(np.mean(err_um[ok] ** 2))),
        "position_max_abs_error_um": _f(np.max(np.abs(err_um[ok]))),
        "mean_sigma_um": _f(np.nanmean(1e3 * est.sigma_s_mm[ok])),
        "z_mean_square": _f(np.mean(z**2)) if z.size else None,
        "injected_outliers": injected,
        "flagged_outliers": flagged,
    }
    if "plane_mm" in truth:
        # what the constant-orientation model can see: displacement at the board plane (Abbe offset = distance)
        plane = np.where(have, truth["plane_mm"][np.maximum(rows, 0)], np.nan)
        plane_err_um = 1e3 * (est.state.s - (plane - plane[est.reference_view]))
        others = ok & (np.arange(obs.K) != est.reference_view)
        zp = plane_err_um[others] / np.maximum(1e3 * est.sigma_s_mm[others], 1e-12)
        out["board_plane_rms_error_um"] = _f(np.sqrt(np.mean(plane_err_um[ok] ** 2)))
        out["board_plane_max_abs_error_um"] = _f(np.max(np.abs(plane_err_um[ok])))
        out["board_plane_z_mean_square"] = _f(np.mean(zp**2)) if zp.size else None
        out["abbe_rms_um"] = _f(1e3 * np.sqrt(np.mean(((plane - axis) - (plane - axis)[est.reference_view])[ok] ** 2)))
        for k, row in enumerate(positions):
            if have[k]:
                row["truth_plane_deviation_um"] = _f(1e3 * (plane[k] - plane[est.reference_view] - nominal[k]))
    return out


def _detrended(
    straight: np.ndarray | None, rows: np.ndarray, have: np.ndarray, ok: np.ndarray, target_mm: np.ndarray
) -> np.ndarray | None:
    """Truth straightness per view (K, 2) minus its least-squares line over the used views."""
    if straight is None:
        return None
    per_view = np.where(have[:, None], straight[np.maximum(rows, 0)], np.nan)
    A = np.stack([np.ones(ok.sum()), target_mm[ok]], axis=1)
    coef = np.linalg.lstsq(A, per_view[ok], rcond=None)[0]
    return per_view - np.stack([np.ones_like(target_mm), target_mm], axis=1) @ coef


def summary_rows(results: dict[str, Any]) -> list[tuple[str, Any, str]]:
    """(name, value, unit) rows for summary.csv and the report's summary table."""
    p = results["parameters"]
    fig = results["figures"]
    single = fig.get("single_run") or {}
    rows: list[tuple[str, Any, str]] = [
        ("method", results["method"], ""),
        ("views", p["n_views"], ""),
        ("views_used", p["n_used"], ""),
        ("outlier_views", p["n_outliers"], ""),
        ("corner_noise_sigma", p["sigma_px"], "px"),
        ("rms_reprojection", p["rms_px"], "px"),
    ]
    for key, unit in (("mean_step_mm", "mm"), ("step_std_um", "um"), ("max_abs_deviation_um", "um"),
                      ("scale_ppm", "ppm"), ("periodic_amplitude_um", "um"), ("periodic_period_mm", "mm")):
        if key in single:
            rows.append((key.rsplit("_", 1)[0] if unit in key else key, single[key], unit))
    iso = fig.get("iso230_2") or {}
    for key in ("A_um", "R_um", "E_um", "B_um", "M_um", "A_up_um", "A_down_um", "R_up_um", "R_down_um", "E_up_um", "E_down_um"):
        if iso.get(key) is not None:
            rows.append((f"iso230_2_{key[:-3]}", iso[key], "um"))
    if fig.get("straightness_span_um"):
        rows.append(("straightness_span_1", fig["straightness_span_um"][0], "um"))
        rows.append(("straightness_span_2", fig["straightness_span_um"][1], "um"))
    for name, value in (fig.get("angles_span_urad") or {}).items():
        rows.append((f"{name}_span", value, "urad"))
    tc = results.get("truth_comparison") or {}
    if tc.get("position_rms_error_um") is not None:
        rows.append(("truth_position_rms_error", tc["position_rms_error_um"], "um"))
        rows.append(("truth_position_max_abs_error", tc["position_max_abs_error_um"], "um"))
    if tc.get("board_plane_rms_error_um") is not None:
        rows.append(("truth_board_plane_rms_error", tc["board_plane_rms_error_um"], "um"))
        rows.append(("truth_abbe_term_rms", tc["abbe_rms_um"], "um"))
    rows.append(("software_version", results["software"]["version"], ""))
    return rows
