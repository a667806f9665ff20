"""`lps demo [--planar]`: the whole simulated rig (one axis, or an XY gantry) end to end, in one command.

Simulate an intrinsics set and calibrate it; capture a bidirectional session
on the paper's rig with a realistic stage error (on a gantry: squareness,
per-axis scale, lead-screw errors and straightness per
:func:`lps_gui.core.truth.simulate.paper_planar_errors`) through the capture engine
and the simulated camera; detect; estimate; write report.pdf and the CSVs;
compare with the simulator's truth; on one axis, close the loop with a
compensated capture. The printed error against truth is results.json's
``truth_comparison`` (one reduction, :func:`lps_gui.sim.truth.reduce_truth`;
the lines are :mod:`lps_gui.pipeline.demos.summary`'s).
"""
from __future__ import annotations

import logging
import shutil
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.planning.plan import Plan
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.truth.realism import printed_rng, realism_named
from lps_gui.core.truth.simulate import SimulationSpec, paper_planar_spec, paper_rig_spec, small_planar_spec, small_spec
from lps_gui.errors import InputError
from lps_gui.io.intrinsics_file import write_intrinsics
from lps_gui.io.results.model import Results
from lps_gui.io.session import Session
from lps_gui.pipeline.demos.steps import estimate_and_report
from lps_gui.pipeline.demos.summary import PAPER_SPEC, planar_summary_lines, summary_lines
from lps_gui.pipeline.detect import detect_session
from lps_gui.pipeline.intrinsics import calibrate_images
from lps_gui.sim.images import simulate_intrinsics_set
from lps_gui.sim.session import create_simulated_session, simulated_engine

log = logging.getLogger(__name__)

MARKER = ".lps-demo"  # a folder the demo made and may clear on the next run
# the simulated board is exact at 20 C; the stage is a little warm (steel screw), as in a lab
DEMO_ENVIRONMENT = {"board_temperature_c": 20.0, "board_cte_ppm_per_k": 23.0, "square_mm_uncertainty_um": 0.1,
                    "stage_temperature_c": 20.5, "stage_cte_ppm_per_k": 11.5,
                    "notes": "simulated rig; board on aluminium composite, values as a lab would record them"}
DEMO_IDENTIFICATION = {"operator": "lps demo", "customer": "demonstration (simulated rig)",
                       "stage_model": "paper's lead-screw stage (simulated)", "location": "simulator"}
BarFactory = Callable[[str], ProgressFn]


@dataclass
class DemoStep:
    """One step of the demo: what ran, or what was skipped and why."""

    name: str
    status: str  # "done", "fallback", "skipped"
    message: str
    seconds: float = 0.0


@dataclass
class DemoResult:
    """Where the demo wrote its files and what it found."""

    out_dir: Path
    session_dir: Path | None = None
    report_pdf: Path | None = None
    csvs: list[Path] = field(default_factory=list)
    reports: list[Path] = field(default_factory=list)  # the compensated session's report, the as-found/as-left PDF
    steps: list[DemoStep] = field(default_factory=list)
    summary: list[str] = field(default_factory=list)
    results: Results | None = None  # the session's results.json as read


def demo_spec(quick: bool, seed: int = 0, planar: bool = False) -> SimulationSpec:
    """The simulated experiment of the demo.

    Full: the paper's rig (1920x1080, 18x30 board 600 mm away, its lead-screw
    stage error) over 50 targets 2 mm apart, both directions, 2 runs (200
    frames: ISO 230-2 figures need two runs; 2 mm resolves the 5 mm screw
    pitch). Quick: the small 640x480 rig, 12 targets, both directions, 2 runs.

    ``planar``, full: the paper's camera over a 7 x 5 grid at 10 mm, forward
    and backward (70 frames: lines of 7 and 5 targets give ISO 230-2 figures
    per axis). Quick: the small rig on a 5 x 3 grid at 10 mm, both directions
    (30 frames).
    """
    if planar:
        stop = (40.0, 20.0) if quick else (60.0, 40.0)
        plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=stop, step_mm=(10.0, 10.0), directions="both",
                       settle_s=0.1, feed_mm_min=3000.0)
        return small_planar_spec(seed=seed, plan=plan) if quick else paper_planar_spec(seed=seed, plan=plan)
    if quick:
        return small_spec(seed=seed, views=12, directions="both", runs=2)
    from lps_gui.core.truth.simulate import paper_stage_errors

    plan = Plan(start_mm=0.0, stop_mm=98.0, step_mm=2.0, directions="both", runs=2)
    return paper_rig_spec(seed=seed, errors=paper_stage_errors(), plan=plan)


def declared_environment(spec: SimulationSpec, base: dict) -> dict:
    """session.json ``environment``: ``base``, its board uncertainty at least the realism's print scale (a user
    declares what the certificate says; the simulated prints are drawn from it)."""
    env = dict(base)
    if spec.realism is not None:
        square = spec.rig.board.square_mm
        env["square_mm_uncertainty_um"] = max(float(env.get("square_mm_uncertainty_um") or 0.0),
                                              1e-3 * spec.realism.print_scale_ppm * square)
    return env


def prepare_out(out: Path) -> None:
    """Make ``out``; clear it only if an earlier demo made it; refuse to touch anything else."""
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        if not (out / MARKER).exists():
            raise InputError(f"{out}: folder is not empty and was not made by `lps demo`; choose another --out")
        for child in out.iterdir():
            if child.name != MARKER:
                shutil.rmtree(child) if child.is_dir() else child.unlink()
    out.mkdir(parents=True, exist_ok=True)
    (out / MARKER).write_text("made by lps demo; cleared by the next run\n")


def run_demo(
    out: Path,
    quick: bool = False,
    bar: BarFactory = lambda label: no_progress,
    cancel: CancelToken | None = None,
    say: Callable[[str], None] = lambda line: None,
    seed: int = 0,
    planar: bool = False,
    travel_mm: float | None = None,
    preset: str | None = None,
    lens_misfit_px: float = 0.0,
    realism: str = "off",
) -> DemoResult:
    """Run the demo into ``out``; every step reports through ``bar(label)`` and ``say``.

    Parameters
    ----------
    out : folder for everything the demo writes (cleared if a previous demo made it).
    quick : the small rig (seconds instead of minutes).
    bar : makes a progress callback per step (the CLI passes a ProgressBar).
    say : prints one line (what a step did or skipped).
    planar : the planar pipeline (SPEC 10) on the simulated XY gantry.
    travel_mm, preset : the whole travel against a row of targets (SPEC 13, :mod:`lps_gui.pipeline.demos.targets`).
    lens_misfit_px : a true lens with rational and thin-prism terms that the 5-coefficient calibration misses by
        this RMS over the image (:mod:`lps_gui.core.truth.lens_misfit`); 0: the 5-coefficient lens.
    realism : "off", "on" or "strong": the simulator's realism switches (:mod:`lps_gui.core.truth.realism`).
    """
    out = Path(out)
    row = travel_mm is not None or preset is not None
    if row:
        from lps_gui.pipeline.demos.targets import row_demo_spec

        spec = row_demo_spec(travel_mm, preset, seed)
    else:
        spec = demo_spec(quick, seed, planar)
    if lens_misfit_px > 0:
        from lps_gui.core.truth.lens_misfit import with_lens_misfit

        spec = with_lens_misfit(spec, lens_misfit_px)
    spec = replace(spec, realism=realism_named(realism))
    prepare_out(out)
    res = DemoResult(out)

    def step(name: str, status: str, message: str, t0: float) -> None:
        res.steps.append(DemoStep(name, status, message, time.monotonic() - t0))
        say(f"{name}: {message}" + (f" ({time.monotonic() - t0:.1f} s)" if status != "skipped" else ""))
        if cancel is not None:
            cancel.check("demo")

    if row:
        from lps_gui.pipeline.demos.targets import run_row_demo

        return run_row_demo(out, spec, res, step, bar, cancel, seed, calibrate_step)
    t0 = time.monotonic()
    intrinsics, message, status = calibrate_step(out, spec, quick, bar("intrinsics"), cancel, seed)
    step("intrinsics", status, message, t0)

    t0 = time.monotonic()
    session, message, status = capture_step(out / "session", spec, intrinsics, bar("capture"), cancel)
    step("capture", status, message, t0)
    res.session_dir = session.folder
    if not planar:
        session.meta["stage_spec"] = dict(PAPER_SPEC)
        session.meta.setdefault("environment", declared_environment(spec, DEMO_ENVIRONMENT))
        session.meta.setdefault("identification", dict(DEMO_IDENTIFICATION))
        session.save_meta()

    t0 = time.monotonic()
    table = detect_session(session.folder, bar("detect"), cancel)
    n_ok = int(np.isfinite(table.corners_px).any(axis=(1, 2)).sum())
    step("detect", "done", f"board found in {n_ok}/{len(table.names)} images", t0)

    results = estimate_and_report(session.folder, res, step, bar, cancel, lambda p: (
        f"{'planar ' if planar else ''}joint LM on {p.n_used}/{p.n_views} views, "
        f"RMS {np.nan if p.rms_px is None else p.rms_px:.3f} px"))
    if planar:
        res.summary = planar_summary_lines(results)
        return res
    res.summary = summary_lines(results, spec)
    # close the loop: compensate, re-capture, re-measure (pipeline/compensation_pass.py)
    from lps_gui.pipeline.compensation_pass import compensation_pass

    t0 = time.monotonic()
    cp = compensation_pass(session.folder, out / "session-compensated", bar("compensated capture"), cancel)
    from lps_gui.report.pdf.compare import write_comparison
    from lps_gui.report.pdf.document import write_report

    res.reports = [write_report(cp.after_dir), write_comparison(session.folder, cp.after_dir)]
    step("compensate", "done", "; ".join(cp.lines()), t0)
    res.summary += cp.lines()
    return res


def calibrate_step(out: Path, spec: SimulationSpec, quick: bool, progress: ProgressFn, cancel: CancelToken | None,
                   seed: int) -> tuple[CameraIntrinsics, str, str]:
    """Render a varied-pose intrinsics set and calibrate it."""
    truth = spec.rig.intrinsics
    n_views = 10 if quick else 15
    folder = out / "intrinsics-set"
    lens = printed = None
    if spec.realism is not None:  # the same true lens; the session's board as printed, or a chessboard of its own
        lens = spec.realism.lens(truth)
        printed = (spec.printed() if spec.layout is None
                   else spec.realism.printed_board(spec.rig.board, printed_rng(seed + 1)))
    paths = simulate_intrinsics_set(folder, spec.rig.board, truth, n_views=n_views, seed=seed + 1,
                                    progress=_first_half(progress), cancel=cancel, lens=lens, printed=printed)
    cal = calibrate_images(paths, spec.rig.board, progress=_second_half(progress), cancel=cancel)
    write_intrinsics(out / "intrinsics.json", cal.intrinsics)
    fx_err = cal.intrinsics.fx - truth.fx
    return (cal.intrinsics,
            f"calibrated from {n_views} simulated views: RMS {cal.rms_px:.3f} px, fx error {fx_err:+.2f} px "
            f"({out / 'intrinsics.json'})", "done")


def _first_half(progress: ProgressFn) -> ProgressFn:
    return lambda done, total, message="": progress(done, 2 * max(total, 1), message)


def _second_half(progress: ProgressFn) -> ProgressFn:
    return lambda done, total, message="": progress(max(total, 1) + done, 2 * max(total, 1), message)


def capture_step(folder: Path, spec: SimulationSpec, intrinsics: CameraIntrinsics, progress: ProgressFn,
                 cancel: CancelToken | None) -> tuple[Session, str, str]:
    """Drive the simulated stage or gantry (simulated time) and camera through the real capture engine.

    Returns (session, message, status).
    """
    session, stage, camera = create_simulated_session(folder, spec, intrinsics=intrinsics)
    stage.connect()
    try:
        summary = simulated_engine(session, stage, camera).run(progress, cancel)
    finally:
        for close in (camera.close, stage.disconnect):
            try:
                close()
            except Exception:  # closing a simulated device must not hide the capture's own result
                log.debug("closing the simulated rig", exc_info=True)
    if summary.error or summary.listed < summary.total:
        raise InputError(f"capture stopped after {summary.listed}/{summary.total} frames: {summary.error or summary.state}; "
                         f"the frames are kept in {folder}")
    session = Session.open(folder)  # the engine folded the per-capture truth into session.json
    if spec.plan.planar:
        return session, (f"captured {len(session.records())} frames on the simulated gantry through the capture engine "
                         f"({session.folder})"), "done"
    return session, f"captured {summary.listed} frames through the capture engine on the simulated rig ({folder})", "done"
