"""`lps demo --travel MM` / `--preset paper-row`: the paper's whole X axis against a row of targets (SPEC 13).

The steps of the one-board demo on a row: calibrate the camera from a
simulated intrinsics set (a chessboard of the targets' squares), render every
stop of the row session (the simulator's truth: mounting errors, targets cut
by the image border at the ends of the travel), detect every target in one
ArUco pass per image, estimate through the one path, write report.pdf and the
CSVs, print the figures beside the truth (positions and target poses).
"""
from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.target_presets import paper_row_spec
from lps_gui.core.progress import CancelToken
from lps_gui.core.truth.simulate import SimulationSpec
from lps_gui.errors import InputError
from lps_gui.io.results.model import Results
from lps_gui.pipeline.demos.steps import estimate_and_report
from lps_gui.pipeline.demos.summary import PAPER_SPEC  # the paper's Table 1

ROW_STEP_MM = 12.7  # the paper's X axis: 1524 mm in 120 steps
# a printed target checked with a steel rule over its 330 mm: 20 um, i.e. 2 um per 30 mm square
ROW_ENVIRONMENT = {"board_temperature_c": 20.0, "board_cte_ppm_per_k": 23.0, "square_mm_uncertainty_um": 2.0,
                   "stage_temperature_c": 20.5, "stage_cte_ppm_per_k": 11.5,
                   "notes": "simulated row; prints on aluminium composite, scale checked with a steel rule"}


def row_demo_spec(travel_mm: float | None, preset: str | None, seed: int = 0) -> SimulationSpec:
    """The paper-row preset, or its geometry over ``travel_mm`` (stops of 12.7 mm, as many targets as the
    planner's rule needs: the views at either end three-quarters covered)."""
    from lps_gui.core.truth.simulate import PRESETS

    if travel_mm is None:
        spec = PRESETS[preset or "paper-row"](seed=seed)
        if spec.layout is None:
            raise InputError(f"demo --preset {preset}: not a row of targets; use paper-row or small-row (or lps demo "
                             "without --preset for the one-board demo)")
        return spec
    if not 0 < travel_mm <= 20000:
        raise InputError(f"demo --travel {travel_mm:g}: give a travel between 0 and 20000 mm")
    stops = max(3, round(travel_mm / ROW_STEP_MM) + 1)
    plan = Plan(start_mm=0.0, stop_mm=float(travel_mm), step_mm=float(travel_mm) / (stops - 1),
                directions="both")  # forward and back: ISO 230-2's bidirectional figures (E, B, M; A indicative)
    return paper_row_spec(seed=seed, plan=plan, n_targets=targets_for_travel(travel_mm))


def targets_for_travel(travel_mm: float, distance_mm: float = 800.0, pitch_mm: float = 340.0,
                       width_mm: float = 330.0) -> int:
    """How many of the paper-row targets cover ``travel_mm`` (core/planning/rows's rule)."""
    from lps_gui.core.planning.rows import view_mm
    from lps_gui.core.planning.target_presets import ROW_CAMERA

    view = view_mm(ROW_CAMERA, distance_mm)[0]
    return max(2, math.ceil((travel_mm + 0.5 * view - width_mm) / pitch_mm) + 1)


def calibration_board(spec: SimulationSpec) -> Board:
    """A chessboard of the targets' squares for the intrinsics set (the set renders plain chessboards)."""
    b = spec.rig.board
    return Board(b.cols, b.rows, b.square_mm)


def run_row_demo(out: Path, spec: SimulationSpec, res: Any, step: Callable[[str, str, str, float], None],
                 bar: Callable[[str], Any], cancel: CancelToken | None, seed: int, calibrate_step: Callable) -> Any:
    """The demo's steps on a row of targets, into ``res`` (a :class:`~lps_gui.pipeline.demos.run.DemoResult`);
    ``calibrate_step`` is the one-board demo's (passed in: the demo imports this module)."""
    from lps_gui.pipeline.detect import detect_session
    from lps_gui.sim.images import simulate_image_session

    t0 = time.monotonic()
    cal_spec = replace(spec, rig=replace(spec.rig, board=calibration_board(spec)))
    intrinsics, message, status = calibrate_step(out, cal_spec, False, bar("intrinsics"), cancel, seed)
    step("intrinsics", status, message, t0)

    t0 = time.monotonic()
    session = simulate_image_session(spec, out / "session", progress=bar("render"), cancel=cancel, intrinsics=intrinsics)
    session.meta.setdefault("environment", dict(ROW_ENVIRONMENT))
    session.meta.setdefault("stage_spec", dict(PAPER_SPEC))  # the paper's Table 1: the row is the paper's X axis
    session.save_meta()
    res.session_dir = session.folder
    T = len(spec.layout.targets)
    step("capture", "done", f"rendered {len(session.records())} stops over {spec.plan.targets()[-1]:g} mm against "
                            f"{T} targets ({session.folder})", t0)

    t0 = time.monotonic()
    table = detect_session(session.folder, bar("detect"), cancel)
    seen = table.seen()
    per = ", ".join(f"{tid} {int((seen[:, j] > 0).sum())}" for j, tid in enumerate(table.targets))
    step("detect", "done", f"targets found in {int((seen.sum(axis=1) > 0).sum())}/{len(table.names)} images "
                           f"(views per target: {per})", t0)

    results = estimate_and_report(session.folder, res, step, bar, cancel, lambda p: (
        f"row model on {p.n_used}/{p.n_views} views and {T} targets, "
        f"RMS {np.nan if p.rms_px is None else p.rms_px:.3f} px"))
    res.summary = row_summary_lines(results)
    return res


def row_summary_lines(results: Results) -> list[str]:
    """What the row demo prints: the fit, the positioning figures, the targets, the truth beside them."""
    from lps_gui.report.pages.summary import fmt, truth_check_lines

    p, single, unc, tc = results.parameters, results.figures.single_run, results.uncertainty, results.truth_comparison
    sig = [v for r in results.positions if (v := r.number("sigma_um"))]
    worst = max((max(t.p_sigma_mm) for t in results.targets if t.p_sigma_mm), default=None)
    settings = (results.raw.get("settings") or {}) if hasattr(results, "raw") else {}
    what = "noise and the self-calibrated intrinsics" if settings.get("self_calibrate") else "noise only"
    lines = [
        f"views: {p.n_views} ({p.n_used} used) against {len(results.targets)} targets; RMS residual {fmt(p.rms_px)} px",
        f"positioning: scale {fmt(single.scale_ppm if single else None)} ppm (sigma "
        f"{fmt(single.scale_sigma_ppm if single else None)}), max |deviation| "
        f"{fmt(single.max_abs_deviation_um if single else None)} \u00b5m, mean step "
        f"{fmt(single.mean_step_mm if single else None, 6)} mm; "
        f"sigma per stop median {fmt(float(np.median(sig)) if sig else None)} \u00b5m ({what})",
        f"targets: poses to {fmt(1e3 * worst if worst is not None else None)} \u00b5m (worst 1-sigma); "
        f"U (k = 2) {fmt(unc.expanded_k2_um if unc else None, 2)} \u00b5m over the travel, with each target's print scale",
    ]
    if tc is not None and tc.position_rms_error_um is not None:
        lines.append(f"error against truth: position RMS {fmt(tc.position_rms_error_um)} \u00b5m, max "
                     f"{fmt(tc.position_max_abs_error_um)} \u00b5m, mean (error/sigma)^2 {fmt(tc.z_mean_square)}"
                     f"; target poses within {fmt(tc.targets.max_abs_z if tc.targets else None)} sigma of truth")
    verdict = (results.raw.get("verdict") or {}) if hasattr(results, "raw") else {}
    if verdict.get("checks"):  # the page-1 verdict against the paper's Table 1, as results.json states it
        lines.append(f"verdict ({verdict.get('decision_rule', '').split(':')[0]}): {verdict.get('overall')}; " + ", ".join(
            f"{c['name']} {c['verdict']}" for c in verdict["checks"]))
    return lines + truth_check_lines(results)
