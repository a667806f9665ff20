"""`lps demo --planar`: the whole planar (XY) pipeline on the simulated gantry, in one command.

Calibrate the camera from a simulated intrinsics set (as the 1-D demo
does), capture rendered images of a grid on the simulated gantry through
the capture engine (squareness, per-axis scale, lead-screw errors and
straightness per :func:`lps_gui.core.planar_simulate.paper_planar_errors`),
detect, estimate the planar model (SPEC 10), write report.pdf and the CSVs.
The figures are printed beside the simulator's truth as results.json's
``truth_comparison`` holds it (one reduction, never recomputed here).
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from lps_gui.core.plan import Plan
from lps_gui.core.simulate import SimulationSpec, paper_planar_spec, small_planar_spec
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.io.session import Session
from lps_gui.pipeline.demo import BarFactory, DemoResult, DemoStep, calibrate_step, prepare_out
from lps_gui.pipeline.detect import detect_session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.session import create_simulated_session, simulated_engine


def planar_demo_spec(quick: bool, seed: int = 0) -> SimulationSpec:
    """The demo's gantry and plan.

    Full: the paper's camera (1920x1080, 30x18 board 600 mm away) over a
    7 x 5 grid at 10 mm, forward and backward (70 frames: lines of 7 and 5
    targets give ISO 230-2 figures per axis). Quick: the small 640x480 rig
    on a 5 x 3 grid at 10 mm, both directions (30 frames).
    """
    if quick:
        plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(40.0, 20.0), step_mm=(10.0, 10.0), directions="both",
                          settle_s=0.1, feed_mm_min=3000.0)
        return small_planar_spec(seed=seed, plan=plan)
    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(60.0, 40.0), step_mm=(10.0, 10.0), directions="both",
                      settle_s=0.1, feed_mm_min=3000.0)
    return paper_planar_spec(seed=seed, plan=plan)


def run_planar_demo(
    out: Path,
    quick: bool = False,
    bar: BarFactory = lambda label: no_progress,
    cancel: CancelToken | None = None,
    say: Callable[[str], None] = lambda line: None,
    seed: int = 0,
) -> DemoResult:
    """Run the planar demo into ``out`` (cleared if an earlier demo made it); steps report through ``bar`` and ``say``."""
    out = Path(out)
    prepare_out(out)
    spec = planar_demo_spec(quick, seed)
    res = DemoResult(out)

    def step(name: str, message: str, t0: float) -> None:
        res.steps.append(DemoStep(name, "done", message, time.monotonic() - t0))
        say(f"{name}: {message} ({time.monotonic() - t0:.1f} s)")
        if cancel is not None:
            cancel.check("demo")

    t0 = time.monotonic()
    intrinsics, message, _ = calibrate_step(out, spec, quick, bar("intrinsics"), cancel, seed)
    step("intrinsics", message, t0)

    t0 = time.monotonic()
    session = capture_planar(out / "session", spec, intrinsics, bar("capture"), cancel)
    res.session_dir = session.folder
    step("capture", f"captured {len(session.records())} frames on the simulated gantry through the capture engine "
                    f"({session.folder})", t0)

    t0 = time.monotonic()
    table = detect_session(session.folder, bar("detect"), cancel)
    n_ok = int(np.isfinite(table.corners_px).any(axis=(1, 2)).sum())
    step("detect", f"board found in {n_ok}/{len(table.names)} images", t0)

    t0 = time.monotonic()
    results = estimate_session(session.folder, method="joint", progress=bar("estimate"), cancel=cancel)
    res.results = results
    p = results.get("parameters") or {}
    step("estimate", f"planar joint LM on {p.get('n_used', '?')}/{p.get('n_views', '?')} views, "
                     f"RMS {float(p.get('rms_px') or np.nan):.3f} px", t0)

    t0 = time.monotonic()
    from lps_gui.report.pdf import write_report

    res.report_pdf = write_report(session.folder, results, progress=bar("report"))
    res.csvs = [session.folder / n for n in ("positions.csv", "summary.csv") if (session.folder / n).exists()]
    step("report", f"{res.report_pdf}", t0)
    res.summary = planar_summary_lines(results)
    return res


def capture_planar(folder: Path, spec: SimulationSpec, intrinsics: Any, progress: ProgressFn,
                   cancel: CancelToken | None) -> Session:
    """Drive the simulated gantry (simulated time) and its camera through the real capture engine."""
    session, stage, camera = create_simulated_session(folder, spec, intrinsics=intrinsics)
    stage.connect()
    try:
        summary = simulated_engine(session, stage, camera).run(progress, cancel)
    finally:
        camera.close()
        stage.disconnect()
    if summary.error or summary.listed < summary.total:
        raise InputError(f"capture stopped after {summary.listed}/{summary.total} frames: "
                         f"{summary.error or summary.state}; the frames are kept in {folder}")
    return Session.open(folder)  # the engine folded the per-capture truth into session.json


def _v(x: Any, digits: int = 1) -> str:
    return "n/a" if x is None else f"{float(x):+.{digits}f}"


def _s(x: Any, digits: int = 1) -> str:
    return "n/a" if x is None else f"{float(x):.{digits}f}"


def planar_summary_lines(results: dict[str, Any]) -> list[str]:
    """What a newcomer reads first: each figure with its sigma, beside the truth from ``truth_comparison``."""
    p = results.get("parameters") or {}
    pl = (results.get("figures") or {}).get("planar") or {}
    tc = results.get("truth_comparison") or {}
    per_axis = pl.get("per_axis") or {}
    lines = [
        f"views: {p.get('n_views', '?')} ({p.get('n_used', '?')} used, {p.get('n_outliers', 0)} flagged outlier(s)); "
        f"RMS residual {_s(p.get('rms_px'), 3)} px",
        f"squareness {_v(pl.get('squareness_urad'))} \u00b1 {_s(pl.get('squareness_sigma_urad'))} \u00b5rad "
        f"({_v(pl.get('squareness_um_per_m'))} \u00b5m/m); truth {_v(tc.get('squareness_urad'))} \u00b5rad"
        + (f" (the stage model's {_v(tc['model_squareness_urad'])}; the truth is the angle of the true path's "
           "least-squares lines, tilted by the axes' straightness)"
           if tc.get("model_squareness_urad") is not None else ""),
    ]
    for axis in ("x", "y"):
        lines.append(f"scale {axis.upper()} {_v(pl.get(f'scale_{axis}_ppm'))} \u00b1 {_s(pl.get(f'scale_{axis}_sigma_ppm'))}"
                     f" ppm; truth {_v(tc.get(f'scale_{axis}_ppm'))} ppm")
    from lps_gui.core.resolution import not_resolved_text

    for axis, other in (("X", "Y"), ("Y", "X")):
        a = per_axis.get(axis) or {}
        st = a.get("straightness") or {}
        value = (f"{_s(a.get('straightness_um_max'), 2)} \u00b5m" if st.get("resolved", True)
                 else not_resolved_text(st.get("noise_span_um"), "\u00b5m"))  # noise alone could give it: no finding
        lines.append(f"straightness of {axis} (along {other}, worst line) {value} "
                     f"(per-point 1-sigma {_s(a.get('straightness_sigma_um'), 2)} \u00b5m); "
                     f"truth {_s(tc.get(f'straightness_{axis.lower()}_um'), 2)} \u00b5m")
    if tc.get("position_rms_error_um") is not None:
        per = tc.get("per_coordinate_rms_error_um") or [None, None]
        lines.append(f"error against truth ({tc.get('reference', '')}): position RMS {_s(tc['position_rms_error_um'], 2)}"
                     f" \u00b5m (x {_s(per[0], 2)}, y {_s(per[1], 2)}), max {_s(tc.get('position_max_abs_error_um'), 2)}"
                     f" \u00b5m; RMS 1-sigma {_s(tc.get('mean_sigma_um'), 2)} \u00b5m; "
                     f"mean (error/sigma)^2 {_s(tc.get('z_mean_square'), 2)}")
    else:
        lines.append("error against truth: no truth")
    return lines
