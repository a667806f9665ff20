"""`lps demo --lightfield`: the light field the stage exists for, end to end on the simulated rig (issue 38).

Calibrate the camera from a simulated intrinsics set; measure a stage with the paper's lead-screw errors
and tilts of 300-600 urad over the travel, the camera mounted a few mrad off the motion (rendered board
images through the capture engine, detection, estimate); write its compensation table; capture the
light-field scene at the measured stops twice, plainly and through the table; build both light fields.
The plain one must refuse the HCI layout (its positions are not uniform), the compensated one writes it,
and the demo reads it back (:func:`lps_gui.io.lightfield_files.read_hci`) and compares every view.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.progress import CancelToken, ProgressFn
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulate import PAPER_INTRINSICS, SimulationSpec, paper_stage_errors, small_spec
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel
from lps_gui.errors import InputError
from lps_gui.io.image_file import read_image
from lps_gui.io.session import Session
from lps_gui.pipeline.lightfield import LightFieldResult, make_lightfield

CAMERA_TILT_DEG = (0.15, -0.1, 0.2)  # the camera's mount: a few mrad off square (about x, y, z)
MOTION_OFF_DEG = (0.2, -0.12)  # the motion's direction against the board (3.5 and 2.1 mrad)


QUICK_PERIODIC_UM = 20.0  # the quick rig's lead screw (the full rig keeps the paper's 4 um)
STAGE_TRAVEL_MM = 1524.0  # the paper's X axis: the tilts run over the whole stage, the light field uses a part


def lightfield_stage_errors(travel_mm: float = STAGE_TRAVEL_MM) -> StageErrorModel:
    """The paper's lead-screw stage (scale, 4 um periodic error at 5 mm, backlash) with tilts of 300-600 urad
    peak to valley over its ``travel_mm``: roll 500 (about the motion), pitch 300, yaw 400, and 2 urad
    more at every stop (the carriage settles a little differently on each visit)."""
    L = float(travel_mm)
    return replace(paper_stage_errors(),
                   roll_urad=ErrorProfile(amplitude=250.0, period_mm=2 * L, phase_rad=-np.pi / 2),
                   pitch_urad=ErrorProfile(poly=(0.0, 300.0 / (L / 1000.0))),
                   yaw_urad=ErrorProfile(amplitude=200.0, period_mm=L), angle_noise_urad=2.0)


def lightfield_spec(quick: bool, seed: int = 0) -> SimulationSpec:
    """The measured rig: quick, the small camera over 12 stops at 2 mm; full, the paper's camera and board
    600 mm away over 50 stops at 2 mm; both directions, two runs (ISO 230-2, and the run scatter)."""
    if quick:
        base = small_spec(seed=seed, views=12, directions="both", runs=2)
        board, intr, distance = base.rig.board, base.rig.intrinsics, 500.0
        plan = base.plan
    else:
        board, intr, distance = Board(cols=30, rows=18, square_mm=10.0), PAPER_INTRINSICS, 600.0
        plan = Plan(start_mm=0.0, stop_mm=98.0, step_mm=2.0, directions="both", runs=2)
    t = plan.targets()
    errors = lightfield_stage_errors()
    if quick:  # the small camera at 500 mm measures a stop to ~5 um: a hobby lead screw's 20 um periodic error shows
        errors = replace(errors, periodic_um=QUICK_PERIODIC_UM)
    rig = Rig.facing_board(board, intr, distance, (t[0], t[-1]), errors=errors,
                           tilt_deg=CAMERA_TILT_DEG, misalignment_deg=MOTION_OFF_DEG)
    return SimulationSpec("lightfield-quick" if quick else "lightfield", rig, plan, seed=seed)


@dataclass
class LightFieldDemo:
    out_dir: Path
    measurement: Path | None = None
    plain: LightFieldResult | None = None
    compensated: LightFieldResult | None = None
    hci_views_equal: bool | None = None
    summary: list[str] = field(default_factory=list)


def capture_scene(folder: Path, measured: Path, table: Path | None, progress: ProgressFn,
                  cancel: CancelToken | None) -> Session:
    """`lps capture --scene` on the simulated rig, through ``table`` when given."""
    from lps_gui.capture.compensated import apply_compensation
    from lps_gui.sim.scene_session import create_scene_session
    from lps_gui.sim.session import simulated_engine

    session, stage, camera = create_scene_session(folder, Session.open(measured))
    stage.connect()
    try:
        engine = simulated_engine(session, stage, camera)
        apply_compensation(engine, session, table)
        summary = engine.run(progress, cancel)
    finally:
        camera.close()
        stage.disconnect()
    if summary.listed < summary.total:
        raise InputError(f"scene capture stopped after {summary.listed}/{summary.total} frames: "
                         f"{summary.error or summary.state}; the frames are kept in {folder}")
    return Session.open(folder)


def check_hci_readback(res: LightFieldResult) -> bool:
    """Read the HCI layout back from its description and compare every view with the rectified one."""
    from lps_gui.io.lightfield_files import read_hci

    assert res.hci is not None
    params, views = read_hci(res.hci.parent)
    doc_views = sorted(res.files[0].parent.joinpath("views").glob("*.png"))
    if len(views) != len(doc_views) or params.num_cams_x * params.num_cams_y != res.n_views:
        return False
    got = {read_image(v).tobytes() for v in views}
    return got == {read_image(v).tobytes() for v in doc_views}


def run_lightfield_demo(out: Path, quick: bool = False, bar: Callable[[str], ProgressFn] = lambda label: (lambda *a: None),
                        say: Callable[[str], None] = lambda line: None, cancel: CancelToken | None = None,
                        seed: int = 0) -> LightFieldDemo:
    """Everything of the module docstring into ``out`` (cleared when an earlier demo made it)."""
    from lps_gui.io.compensation_file import write_table
    from lps_gui.pipeline.compensate import session_results, table_from_results
    from lps_gui.pipeline.demos.run import calibrate_step, capture_step, prepare_out
    from lps_gui.pipeline.detect import detect_session
    from lps_gui.pipeline.estimate import estimate_session

    out = Path(out)
    spec = lightfield_spec(quick, seed)
    prepare_out(out)
    res = LightFieldDemo(out)

    def step(name: str, message: str, t0: float) -> None:
        say(f"{name}: {message} ({time.monotonic() - t0:.1f} s)")
        if cancel is not None:
            cancel.check("demo")

    t0 = time.monotonic()
    intrinsics, message, _ = calibrate_step(out, spec, quick, bar("intrinsics"), cancel, seed)
    step("intrinsics", message, t0)
    t0 = time.monotonic()
    session, message, _ = capture_step(out / "measurement", spec, intrinsics, bar("measure"), cancel)
    detect_session(session.folder, bar("detect"), cancel)
    estimate_session(session.folder, cancel=cancel)
    res.measurement = session.folder
    p = session_results(session.folder, "lightfield").parameters
    step("measurement", f"{message}; joint LM on {p.n_used}/{p.n_views} views, RMS {p.rms_px:.3f} px", t0)
    t0 = time.monotonic()
    table_path = write_table(out / "compensation.csv", table_from_results(session_results(session.folder)), "csv")
    step("compensation", f"table from the measurement: {table_path}", t0)
    for name, table in (("scene", None), ("scene-compensated", table_path)):
        t0 = time.monotonic()
        scene = capture_scene(out / name, session.folder, table, bar(name), cancel)
        step(name, f"{len(scene.records())} views of the scene at the measured stops"
             + (" through the compensation table" if table else ""), t0)
        t0 = time.monotonic()
        lf = make_lightfield(scene.folder, out / name.replace("scene", "lightfield"), progress=bar("light field"),
                             cancel=cancel)
        if table is None:
            res.plain = lf
        else:
            res.compensated = lf
        step(f"light field of {name}", f"{lf.n_views} views rectified; "
             + (f"HCI layout in {lf.hci.parent}" if lf.hci else (lf.refusal or "")), t0)
    if res.compensated is not None and res.compensated.hci is not None:
        res.hci_views_equal = check_hci_readback(res.compensated)
    res.summary = summary_lines(res)
    return res


def summary_lines(res: LightFieldDemo) -> list[str]:
    from lps_gui.pipeline.lightfield import check_lines

    lines: list[str] = []
    if res.plain is not None:
        lines.append("without compensation: " + (res.plain.refusal or "HCI layout written (positions uniform)"))
        lines += [f"  {s}" for s in check_lines(res.plain.check)]
    if res.compensated is not None:
        c = res.compensated
        lines.append(f"with compensation: positions within {float(c.grid.z.max()):.1f} sigma of a uniform grid; "
                     + (f"HCI layout written and read back ({'every view identical' if res.hci_views_equal else 'MISMATCH'})"
                        if c.hci else (c.refusal or "")))
        lines += [f"  {s}" for s in check_lines(c.check)]
    return lines


def report_paths(res: LightFieldDemo) -> list[Any]:
    from lps_gui.report.pdf.lightfield import REPORT_FILE

    return [r.out / REPORT_FILE for r in (res.plain, res.compensated) if r is not None]
