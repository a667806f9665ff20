"""Estimate a session: read its files, run the estimator, write results (SPEC 7, SPEC 10).

The only way from a session to results, for a stage of one or two axes:
reads session.json, captures.jsonl and corners.vnl (board at the session's
temperature, with its warp; stale and collinear corners refused), runs
:func:`lps_gui.core.estimator.estimate.estimate` (the solver chosen by the number of
axes D), adds the accuracy figures (a line's here, a plane's in
:mod:`lps_gui.pipeline.results.planar`), the environment and uncertainty
budget and, for a simulated session, the error against truth, and writes
results.json, positions.csv and summary.csv under the session lock.
Everything is computed before anything is written, so a failure leaves the
session as it was.
"""
from __future__ import annotations

import time
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.estimator.board_plane_positions import POSITION_MODEL_BOARD_PLANE
from lps_gui.core.estimator.estimate import EstimateOptions, LpsEstimate, estimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.geometry.rotation import log_so3
from lps_gui.core.models.hybrid import HybridOptions
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.gc_tuning import paused as paused_collections
from lps_gui.io.board_file import board_to_dict
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.io.intrinsics_file import apply_board_warp, intrinsics_to_dict
from lps_gui.io.results.document import (assemble_results, in_section_order, json_floats, rows_from_columns,
                                         write_results)
from lps_gui.io.results.document import json_float as _f
from lps_gui.io.results.history import commit_results
from lps_gui.io.session import Session
from lps_gui.io.session_lock import SessionLock
from lps_gui.pipeline.results.asme import asme_results, test_options
from lps_gui.pipeline.results.board_plane import position_columns, straightness_figures
from lps_gui.pipeline.results.error_motions import error_motions_outcome
from lps_gui.pipeline.results.parts import AxisResults
from lps_gui.pipeline.results.planar import build_planar_results
from lps_gui.pipeline.results.uncertainty import BudgetSource, environment_and_uncertainty
from lps_gui.pipeline.results.verdict import measured, summary_rows, verdict_section
from lps_gui.pipeline.session_checks import corners_of_records, session_inputs
from lps_gui.pipeline.session_input import SessionInput, read_session_input
from lps_gui.pipeline.target_session import target_observations, targets_with_truth
from lps_gui.sim.truth import truth_comparison
from lps_gui.sim.truth_figures import CheckedValues, self_check_section
from lps_gui.io.results.keys import DEVIATION_UM, MEASURED_MM, SIGMA_TOTAL_UM
from lps_gui.io.results.sections import Figures, Flag, Parameters, Position, TruthComparison

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


def observations_from_session(source: SessionInput | Session, intrinsics: CameraIntrinsics | None = None
                              ) -> Observations:
    """Match every line of captures.jsonl to its corners in corners.vnl, for a stage of one or two axes.

    The board is the one at the session's temperature (environment), bowed as
    the intrinsics calibration found it; corners of replaced images and views
    whose corners lie on one line are refused. A planar session takes every
    capture's per-axis approach side from its plan. ``source``: the session as
    read once (:func:`~lps_gui.pipeline.session_input.read_session_input`), or an open session read here.
    """
    inp = source if isinstance(source, SessionInput) else read_session_input(source, intrinsics=intrinsics)
    intr = intrinsics or inp.intrinsics
    records = list(inp.records)
    if not records:
        raise InputError(f"{inp.captures_path}: no captures listed; capture or simulate a session first")
    if inp.planar:
        for r in records:
            if not isinstance(r.target_mm, tuple):
                raise InputError(f"{inp.captures_path}: capture {r.index} has target_mm {r.target_mm!r}, "
                                 "not [x, y]; a planar session (plan.axes [X, Y]) lists both coordinates")
    if inp.meta.get("targets") is not None:  # a row or constellation (SPEC 13)
        return target_observations(inp, intr, records, approach_of(inp, records))
    board = apply_board_warp(inp.measured_board, intr)
    table = read_corners_vnl(inp.corners_path, board.n_corners)
    corners = corners_of_records(inp, table, records)
    check_corner_layout(inp, board, intr, records, corners)
    obs = observations_of_views(inp.corners_path, board, intr, records, corners, table.sha256,
                                approach_of(inp, records))
    if not inp.planar and inp.plan.segments:  # one board moved between segments (SPEC 13 stitching)
        from lps_gui.pipeline.stitched_session import stitched_observations

        return stitched_observations(inp, obs, records)
    return obs


def check_corner_layout(session: SessionInput, board: Any, intr: CameraIntrinsics, records: list[Any],
                        corners: np.ndarray) -> None:
    """One line naming the first view whose corners are reversed, mirrored or outside the intrinsics' image."""
    from lps_gui.core.corner_layout import layout_problems

    problems = layout_problems(corners, board.cols, board.rows, tuple(intr.image_size))
    if problems:
        k, why = problems[0]
        more = f" (and {len(problems) - 1} other view(s))" if len(problems) > 1 else ""
        raise InputError(f"{session.corners_path}: view {records[k].file}: {why}{more}; nothing estimated: run "
                         f"`lps detect {session.folder} --force`, or check the intrinsics")


def observations_of_views(corners_path: Path, board: Any, intr: CameraIntrinsics, records: list[Any],
                          corners: np.ndarray, sha256: str | None = None, approach: list | None = None
                          ) -> Observations:
    """The observations of ``records`` with their ``corners`` (K, N, 2): the file's, or a live capture's so far."""
    return Observations(
        board=board,
        intrinsics=intr,
        corners_px=corners,
        target_mm=[r.target_mm for r in records],
        direction=[1.0 if r.direction == "+" else -1.0 for r in records],
        run=[r.run for r in records],
        index=[r.index for r in records],
        names=[r.file for r in records],
        source=str(corners_path),
        source_sha256=sha256,
        approach=approach,
    )


def approach_of(session: SessionInput, records: list) -> list | None:
    """Every capture's per-axis approach side from a planar session's plan (None on one axis)."""
    if not session.planar:
        return None
    approach_by_index = {s.index: s.approach for s in session.plan.stops()}
    return [approach_by_index.get(r.index, (1, 1)) for r in records]


def resolve_self_calibration(opt: EstimateOptions, obs: Observations) -> EstimateOptions:
    """``self_calibrate`` None (not chosen): a session with targets self-calibrates, others do not.

    Why: on a row the chain of ties carries an intrinsics error along the whole travel (an aspect error turns
    every target about its vertical axis), far beyond the corner noise the per-stop sigma shows; the row
    itself fixes the intrinsics to a fraction of their prior (docs/targets.md). The paper's X axis rendered
    (`lps demo --travel 1524 --seed 2`): position error 5.1 um RMS against a per-stop sigma of 0.94 um with
    the calibrated intrinsics held, 1.5 um self-calibrated; target poses 9.3 sigma from truth, 2.0. Without
    the calibration's covariance there is no prior, and a stitched capture (one board moved between segments)
    holds them: held, as before.
    """
    if opt.self_calibrate is not None:
        return opt
    auto = (obs.mounted is not None and obs.segment is None  # a stitched capture holds them (one board moved)
            and obs.intrinsics.covariance is not None and opt.method == "joint")
    return replace(opt, self_calibrate=auto)


def estimate_with_self_calibration(obs: Observations, opt: EstimateOptions, progress: ProgressFn = no_progress,
                                   cancel: CancelToken | None = None) -> Any:
    """The estimate, self-calibrated where :func:`resolve_self_calibration` defaults a row to it and the row model
    fits: with the intrinsics held first, a row whose model leaves the stage's angles (the positions then come
    from every stop's own pose, ``position_model`` "board plane") keeps that estimate. Why: freed intrinsics
    inside a model of one orientation absorb the stage's angles, and the self-calibrated solve never switches
    to the board-plane positions (core/estimator/target_estimate.py: the switch is for held intrinsics); on a
    stage the row model fits they fix the chain's scale (the paper axis: position z^2 27 -> 2.4). The price: a
    defaulted row is solved twice (held, then self-calibrated)."""
    chosen = resolve_self_calibration(opt, obs)
    if not chosen.self_calibrate or opt.self_calibrate is not None:  # held, or what the user asked for
        return estimate(obs, chosen, progress, cancel)
    held = estimate(obs, replace(opt, self_calibrate=False), progress, cancel)
    if held.position_model == POSITION_MODEL_BOARD_PLANE:
        return held
    return estimate(obs, chosen, progress, cancel)


def estimate_session(
    session_dir: Path | str,
    method: str = "joint",
    options: dict[str, Any] | EstimateOptions | None = None,
    intrinsics_path: Path | str | None = None,
    out_dir: Path | str | None = None,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> dict[str, Any]:
    """Estimate a session folder of one or two axes and write results.json, positions.csv, summary.csv.

    The one way from a session to its results: the board correction
    (thermal, warp) and the input checks in :func:`observations_from_session`,
    :func:`~lps_gui.core.estimator.estimate.estimate` with the solver of D axes, the
    uncertainty budget, the session lock while writing. Returns the
    results.json content.
    """
    t0 = time.perf_counter()
    inp = read_session_input(session_dir, intrinsics_path)  # the session read once; every builder is given it
    opt = test_options(inp, make_options(method, options))  # a settling test's frames move by design
    obs = observations_from_session(inp)
    est = estimate_with_self_calibration(obs, opt, progress, cancel)  # a row refines its intrinsics (see there)
    with paused_collections():  # results are trees of dicts and lists: nothing for the cyclic collector
        results = build_results(inp, obs, est, intrinsics_source=str(intrinsics_path or "session.json"))
        results["timings_s"] = {**results["timings_s"], "pipeline_total": time.perf_counter() - t0}  # a new dict: the builders' left as they were
        if cancel is not None:
            cancel.check("estimation")
        with SessionLock(inp.folder) if not out_dir else nullcontext():  # one writer per session
            _write_keeping_history(inp.session, out_dir, results)
    return results


def _write_keeping_history(session: Session, out_dir: Path | str | None, results: dict[str, Any]) -> None:
    """Write the result set; into the session folder, the previous set is kept (results/<time>-<method>/)."""
    if out_dir is None:
        session.check_present()  # moved or removed while estimating: a new folder must not appear at the old path
        commit_results(session.folder, results)  # history copy first, then one journaled commit of the set
    else:
        write_results(Path(out_dir), results)


# ----------------------------------------------------------------------------- results

def build_results(session: SessionInput, obs: Observations, est: LpsEstimate, intrinsics_source: str
                  ) -> dict[str, Any]:
    """The results.json document of an estimate of D axes, with its environment and uncertainty budget.

    Every section after the axis's own is computed from the values the builders made, passed down here (positions,
    figures, flags, truth comparison, U, the ASME test), and written into the document once: no builder reads the
    document it is building back (``tests/pipeline/test_builders_read_no_document.py``).
    """
    part = RESULTS_BY_AXES[obs.D](session, obs, est, intrinsics_source)
    results = dict(part.document)  # a new document, written below, never read: the axis builder's is left as it was
    positions, figures, flags, truth = part.positions, part.figures, part.flags, part.truth_comparison
    targets = targets_truth = None
    if obs.mounted is not None:  # SPEC 13: each target's pose, sigma, views, ties
        targets, targets_truth = targets_with_truth(obs, est, session)
        if obs.segment is not None:  # a stitched session's placements are tied by their repeated stops
            from lps_gui.pipeline.stitched_session import with_stitch_ties

            targets = with_stitch_ties(targets, obs)
        results["targets"] = targets
    motions = error_motions_outcome(session, obs, est, positions, figures, flags)  # SPEC 14, where poses allow
    if motions is not None:
        positions, figures, flags = motions.positions, motions.figures, motions.flags
        results["error_motions"] = motions.section
    if obs.D == 1 and session.truth is not None:  # a line's, once, after the error motions: its z test scores the
        drawn = np.asarray([r.get(SIGMA_TOTAL_UM) for r in positions], dtype=float)  # sigma the bands draw (lens in)
        section, positions = truth_comparison(obs, est, session.truth, positions, drawn_sigma_um=drawn)
        truth = results["truth_comparison"] = TruthComparison.of(**section).to_dict()
    if targets_truth is not None:
        truth = results["truth_comparison"] = {**(truth or {}), "targets": targets_truth}
    board = {**part.board, "square_mm": session.nominal_board.square_mm}  # nominal (20 C); environment.square_mm_used
    results["board"] = board  # is the size used
    results["positions"] = positions = [Position.of(**row).to_dict() for row in positions]  # as the readers read them
    results["figures"] = figures
    budget = BudgetSource(  # the values the builders made, passed on (the budget reads no document)
        positions=positions, parameters=part.parameters, board=board, figures=figures,
        axes=("X",) if obs.D == 1 else ("X", "Y"), resolved=None if motions is None else motions.section.get("resolved"),
        targets=targets, stage_spec=session.meta.get("stage_spec"),
        stitched=bool((session.meta.get("plan") or {}).get("segments")))
    environment, uncertainty = environment_and_uncertainty(budget, session)  # GUM budget, U (k = 2) per figure
    uncertainty_section = uncertainty.to_dict()
    results["environment"], results["uncertainty"] = environment.to_dict(), uncertainty_section
    asme = None
    if obs.D == 1:  # ASME B5.64 names, TUR, tests
        asme = asme_results(session, obs, est, figures, uncertainty)
        results["asme_b5_64"] = asme.to_dict()
    # the verdict, U (k = 2) and the decision rule, machine-readable (line or plane)
    results["verdict"] = verdict_section(measured(budget.axes, figures, uncertainty, asme), session.meta.get("stage_spec"))
    check, flag = self_check_section(CheckedValues(  # a simulated session: does its truth contradict a figure or a finding?
        positions, figures, uncertainty_section, truth, None if motions is None else motions.section, obs.D == 2,
        results.get("asme_b5_64")))
    if check is not None:
        results["truth_comparison"] = {**truth, "self_check": check}
    results["flags"] = [*flags, flag] if flag is not None else flags
    results = in_section_order(results)  # each section in its place (io.results.document.SECTIONS)
    results["summary"] = summary_rows(results)  # summary.csv: a view of the finished document, made last
    return results


def line_results(session: SessionInput, obs: Observations, est: LpsEstimate, intrinsics_source: str) -> AxisResults:
    """The results.json document of one axis and its values: its parts computed here, assembled by
    :func:`lps_gui.io.results.document.assemble_results`."""
    positions = position_rows(obs, est)
    board, parameters = board_to_dict(obs.board), estimate_parameters(obs, est)
    figures, flags = session_figures(obs, est), [Flag.of(**f).to_dict() for f in est.flags]
    results = assemble_results(
        method=est.method,
        settings=est.options.to_dict(),
        inputs=session_inputs(session, intrinsics_source, {session.corners_path.name: obs.source_sha256}),
        board=board,
        intrinsics=intrinsics_to_dict(obs.intrinsics),
        session_meta={k: session.meta.get(k) for k in ("camera", "stage", "plan", "stage_spec", "created") if k in session.meta},
        parameters=parameters,
        positions=positions,
        figures=figures,
        flags=flags,
        timings_s=dict(est.timings_s),
    )
    return AxisResults(results, parameters, board, positions, figures, flags, None)  # truth: after the error motions


def position_rows(obs: Observations, est: LpsEstimate) -> list[dict[str, Any]]:
    """results.json ``positions``: one row per capture, in capture order.

    Built column by column (numpy, then one list per key) and zipped into
    rows: a loop over K views x 40 fields of float() calls is slow at large K.
    """
    dev_um = est.deviation_um(obs.target_mm)
    usable = np.asarray(est.usable, dtype=bool)
    six = est.six_dof
    missing = np.full(obs.K, np.nan)
    columns: dict[str, list[Any]] = {
        "index": np.asarray(obs.index).astype(int).tolist(),
        "run": np.asarray(obs.run).astype(int).tolist(),
        "direction": ["+" if d > 0 else "-" for d in np.asarray(obs.direction).tolist()],
        "target_mm": np.asarray(obs.target_mm, dtype=float).tolist(),
        MEASURED_MM: json_floats(np.where(usable, est.state.s + obs.target_mm[est.reference_view], missing)),
        DEVIATION_UM: json_floats(np.where(usable, dev_um, missing)),
        "sigma_um": json_floats(1e3 * est.sigma_s_mm),
        SIGMA_TOTAL_UM: json_floats(1e3 * est.sigma_total_mm),
        "step_sigma_um": json_floats(1e3 * est.step_sigma_mm),
        "rms_px": json_floats(est.rms_px),
        "n_corners": np.asarray(est.n_corners).astype(int).tolist(),
        "outlier": np.asarray(est.outlier).astype(bool).tolist(),
        "outlier_reason": [reason or ("" if ok else "board not found")
                           for reason, ok in zip(est.outlier_reason, usable.tolist())],
        "used": np.asarray(est.used).astype(bool).tolist(),
        "file": list(obs.names),
    }
    columns.update(position_columns(est))  # straightness at the board plane (SPEC 11), image rotation
    if six is not None:
        for j, key in enumerate(("roll", "pitch", "yaw")):
            columns[f"{key}_urad"] = json_floats(six.angles_urad[:, j])
            columns[f"{key}_sigma_urad"] = json_floats(six.angles_sigma_urad[:, j])
    return rows_from_columns(columns)


def session_figures(obs: Observations, est: LpsEstimate) -> dict[str, Any]:
    """results.json ``figures``: SPEC 5 figures of the deviations, straightness and angle spans."""
    from lps_gui.core.metrology.iso230 import figures_for_session
    from lps_gui.core.metrology.iso230_run import fit_weights_sigma_um

    dev_um = est.deviation_um(obs.target_mm)
    six = est.six_dof
    valid = est.used & np.isfinite(dev_um)
    sigma_um = fit_weights_sigma_um(1e3 * est.sigma_s_mm, valid)  # the reference's 0 (the gauge) as a typical one
    figures = figures_for_session(obs.target_mm, obs.direction, obs.run, dev_um, valid=valid, sigma_um=sigma_um)
    if figures.get("iso230_2"):  # the camera's noise inflates s_j and the extremes: take it out (issue 35)
        from lps_gui.core.metrology.iso230_noise import (
            apply_noise_correction,
            independent_sigma_um,
            noise_corrected_iso,
        )

        corr = noise_corrected_iso(obs.target_mm, obs.direction, obs.run, dev_um, valid, independent_sigma_um(sigma_um))
        figures["iso230_2"] = apply_noise_correction(figures["iso230_2"], corr)
    single = figures.get("single_run")
    if single is not None and single.get("max_abs_deviation_um") is not None:  # a max over noisy deviations too
        from lps_gui.core.metrology.iso230_noise import noise_corrected_max_abs

        single.update(noise_corrected_max_abs(dev_um, valid, sigma_um))
    if single is not None and valid.sum() >= 3:
        single.update(scale_with_uncertainty(obs, est, valid, sigma_um))
    if valid.any():
        figures.update(straightness_figures(obs.target_mm, est, valid, obs.corners_px))
    if six is not None and valid.any():
        figures["angles_span_urad"] = dict(zip(("roll", "pitch", "yaw"), (_f(v) for v in np.ptp(six.angles_urad[valid], axis=0))))
    return Figures.of(**figures).to_dict()  # written through the readers' definition


def estimate_parameters(obs: Observations, est: LpsEstimate) -> dict[str, Any]:
    """results.json ``parameters``: the line, its sigmas and the fit's statistics."""
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
        "rms_um_at_board": rms_um_at_board(obs, est),
        "n_views": obs.K,
        "n_used": int(est.used.sum()),
        "n_outliers": int(est.outlier.sum()),
        "n_observations": est.n_observations,
        "dof": est.dof,
        "iterations": est.iterations,
        "converged": est.converged,
        "reference_index": int(obs.index[est.reference_view]),
    }
    if est.line_model_sigma_px is not None:  # the line model left more than noise: positions of the per-view fit
        parameters["position_model"] = est.position_model
        parameters["line_model_sigma_px"] = est.line_model_sigma_px
    elif est.position_model != "line":  # the line model's positions with the per-view poses' scale
        parameters["position_model"] = est.position_model
    if est.options.self_calibrate:
        parameters["intrinsics_estimated"] = dict(zip(INTRINSIC_NAMES, est.state.intrinsics.vector().tolist()))
    return Parameters.of(**parameters).to_dict()


def rms_um_at_board(obs: Observations, est: LpsEstimate) -> float | None:
    """The RMS reprojection error as a length at the board (um): each used view's RMS (px) times its board
    centre's depth over the focal length, what a pixel of corner error is on the board, where the stage is."""
    line, intr = est.state.line(), est.state.intrinsics
    centre = obs.board.object_points().mean(axis=0)
    depth = (line.R_cam_board @ centre)[2] + line.l0_cam[2] + est.state.s * line.n_cam[2]  # mm, per view
    used = np.asarray(est.used, bool) & np.isfinite(est.rms_px)
    if not used.any():
        return None
    return _f(1e3 * np.sqrt(np.mean((est.rms_px[used] * depth[used] / (0.5 * (intr.fx + intr.fy))) ** 2)))


def scale_with_uncertainty(obs: Observations, est: LpsEstimate, valid: np.ndarray, sigma_um: np.ndarray) -> dict[str, Any]:
    """The scale error's sigma from the full covariance, for the one (weighted) scale fit of ``core.iso230_run``.

    The slope is the linear functional :func:`~lps_gui.core.metrology.iso230_run.scale_functional`
    of the deviations (one offset per run and direction: backlash is not
    scale; weights 1/sigma^2 as in the figures). Its sigma counts the
    correlations between positions (from the board distance and direction)
    and, in total, the intrinsics: a focal-length error is a pure scale error.
    """
    from lps_gui.core.metrology.iso230_run import scale_functional

    groups = obs.run * 2 + (obs.direction > 0)
    row = scale_functional(obs.target_mm[valid], groups[valid], 1.0 / sigma_um[valid] ** 2)
    if row is None:
        return {}
    slope_row = np.zeros(obs.K)
    slope_row[valid] = row  # slope (mm/mm) = slope_row @ positions (mm); the nominal travel only shifts it
    sigma_noise, sigma_total = est.linear_functional_sigma(slope_row)
    return {"scale_sigma_ppm": _f(1e6 * sigma_noise), "scale_sigma_total_ppm": _f(1e6 * sigma_total)}


RESULTS_BY_AXES = {1: line_results, 2: build_planar_results}  # the results.json parts of a stage of D axes
