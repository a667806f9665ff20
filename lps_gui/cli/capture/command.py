"""`lps capture`: run a capture plan on a stage and a camera into a session folder; resume after any stop.

Examples::

    lps capture --out run1                                   # simulated rig, preset "small"
    lps capture --preset paper-rig --directions both --runs 2 --out run2
    lps capture --stage grbl:/dev/ttyUSB0 --camera 0 --plan plan.json \\
                --board board.json --intrinsics intrinsics.json --out run3
    lps capture --resume run3 [--stage grbl:/dev/ttyUSB0 --camera 0]
    lps capture --intrinsics-views 15 --camera 0 --board board.json --out intr   # hand-held board, guided
    lps capture --planar --grid 0,0:40,20:10,10 --directions both --out xy1       # simulated XY gantry (SPEC 10)
    lps capture --planar --preset paper-planar --out xy2                             # the paper's 15 x 9 grid
    lps capture --planar --targets-xy "0,0;20,0;20,10;0,10" --stage emulator --out xy3
    lps capture --planar --iso-lines --grid 0,0:40,20:10,10 --out xy4                # ISO 230-2 lines per axis
    lps capture --planar --stage grbl:/dev/ttyUSB0 --camera 0 --board board.json --grid ... --out xy5
    lps capture --scene run2 --compensation comp.csv --out scene2              # light-field scene (no board)

One command for one axis and two: the plan comes from :mod:`lps_gui.cli.capture.plan`, the devices
from :mod:`lps_gui.cli.capture.devices`; a plan with two axes runs on the simulated gantry (or the
operator's XY stage) through the same engine.
"""
from __future__ import annotations

import argparse

from lps_gui.cli.capture.devices import (
    bind_simulated_stage,
    bind_stage,
    clock,
    close,
    device_session,
    open_devices,
    open_operator_stage,
    preflight,
    read_intrinsics,
    release_lock,
)
from lps_gui.cli.capture.plan import (
    ISO_LEVELS,
    ISO_RUNS,
    build_planar_plan,
    describe,
    line_plan,
    planar_preset_name,
    wants_planar,
)
from lps_gui.cli.option_types import (
    finite,
    float_range,
    int_range,
    nonnegative_finite,
    nonnegative_int,
    positive_finite,
)

HELP = "capture a session: move the stage through a plan and store an image per stop (resumable)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from lps_gui.hardware.registry import specs_help

    p.add_argument("--stage", default=None, help=f"{specs_help()} (default sim; with --camera sim any stage moves "
                   "the simulated rig too)")
    p.add_argument("--camera", default=None, help="sim | N (device index) | genicam:SERIAL | pylon:SERIAL | gphoto2:[PORT] | "
                   "v4l2:/dev/videoN | DIR (replay a folder) | FILE | URL (default sim)")
    p.add_argument("--cti", metavar="PATH", help="genicam: the GenTL producer (.cti) of the camera vendor (default: GENICAM_GENTL64_PATH)")
    p.add_argument("--out", metavar="SESSION", help="new session folder")
    p.add_argument("--resume", metavar="SESSION", help="continue this session at the first frame not listed")
    g = p.add_argument_group("plan (a --plan file, switches override its fields)")
    g.add_argument("--plan", metavar="FILE", help="plan JSON (fields of the plan, or a session.json)")
    g.add_argument("--start", type=finite, dest="start_mm", help="first target, mm")
    g.add_argument("--stop", type=finite, dest="stop_mm", help="last target, mm")
    g.add_argument("--step", type=finite, dest="step_mm", help="target spacing, mm")
    g.add_argument("--targets", help="explicit targets, comma separated mm")
    g.add_argument("--directions", choices=("+", "-", "both"), help="approach direction(s) of the runs")
    g.add_argument("--runs", type=int, help="number of runs (per direction)")
    g.add_argument("--overshoot", type=float, dest="overshoot_mm", help="overshoot before a run's first target, mm")
    g.add_argument("--settle", type=float, dest="settle_s", help="wait after each move, s")
    g.add_argument("--frames", type=int, dest="frames_per_stop", help="frames per stop")
    g.add_argument("--feed", type=float, dest="feed_mm_min", help="feed of the moves, mm/min")
    g.add_argument("--segment-stops", type=int_range(3, 100_000), metavar="N",
                   help="one board moved along the travel (docs/targets.md, stitching): segments of N stops; the "
                        "capture pauses between them for the board to be moved")
    g.add_argument("--overlap-stops", type=int_range(1, 100_000), default=3, metavar="M",
                   help="with --segment-stops: each segment repeats the last M stops of the one before (default 3)")
    g.add_argument("--intrinsics-views", type=int_range(3, 1000), metavar="N", help="guided intrinsics mode: N varied views of a hand-held board into --out (no stage)")
    s = p.add_argument_group("set-up")
    s.add_argument("--board", metavar="FILE", help="board.json (required with a real camera)")
    s.add_argument("--intrinsics", metavar="FILE", help="intrinsics (JSON or OpenCV YAML), embedded into session.json")
    s.add_argument("--preset", default="small", help="simulated rig: small | paper-rig | paper-synthetic (default small)")
    s.add_argument("--seed", type=nonnegative_int, default=0, help="simulated rig: seed of all noise")
    s.add_argument("--noise-grey", type=nonnegative_finite, default=2.0, help="simulated camera: noise sigma, grey levels")
    s.add_argument("--real-time", action="store_true", help="simulated rig: move and settle in real time (default: simulated time)")
    s.add_argument("--time-scale", type=float_range(1e-3, 1e6), default=1.0, help="--stage emulator: simulated time runs this many times faster than real")
    s.add_argument("--encode", default=".png", help="image format (lossless): .png (default), .tif, .bmp")
    lock = s.add_mutually_exclusive_group()
    lock.add_argument("--home", action="store_true", help="a stage locked in Alarm (GRBL powers up so with homing on) is homed ($H) first")
    lock.add_argument("--unlock", action="store_true", help="a stage locked in Alarm is unlocked ($X) first, without homing")
    from lps_gui.cli.capture.setup import add_setup_arguments

    add_setup_arguments(p)
    from lps_gui.cli.capture.asme_test import add_test_arguments

    add_test_arguments(p)
    from lps_gui.cli.capture.live import add_live_arguments

    add_live_arguments(p)
    from lps_gui.cli.capture.scene import add_scene_arguments

    add_scene_arguments(p)
    a = p.add_argument_group("settle detection and averaging")
    a.add_argument("--settle-px", type=positive_finite, metavar="PX", help="before each stop's frame, grab until consecutive frames show the "
                   "board within PX pixels (mean corner shift), e.g. 0.02")
    a.add_argument("--settle-timeout-s", type=positive_finite, default=10.0, metavar="S", help="give up settling after S seconds and take the frame (default 10)")
    a.add_argument("--settle-frames", type=int_range(2, 100), default=3, metavar="N", help="N consecutive frames must agree (default 3; 2: one pair)")
    a.add_argument("--average-frames", type=int_range(1, 1000), default=1, metavar="N", help="store the pixel mean of N frames per image (noise / sqrt(N))")
    s.add_argument("--compensation", metavar="FILE", help="command each target through this table's inverse (lps compensate --format csv|linuxcnc|linuxcnc-offsets)")
    g = p.add_argument_group("planar XY plans (docs/planar.md); --grid, --targets-xy or --iso-lines imply --planar")
    g.add_argument("--planar", action="store_true",
                   help="an XY gantry: a grid over both axes (simulated: presets small-planar, paper-planar)")
    g.add_argument("--grid", metavar="X0,Y0:X1,Y1:DX,DY", help="planar grid: start, stop and step in mm")
    g.add_argument("--pattern", choices=("serpentine", "raster"), help="planar grid order (default serpentine)")
    g.add_argument("--targets-xy", metavar="X,Y;X,Y;...", help="explicit planar targets in mm, in visiting order")
    g.add_argument("--iso-lines", action="store_true",
                   help=f"ISO 230-2 lines on the grid: along X at {ISO_LEVELS} Y levels and along Y at {ISO_LEVELS} "
                        f"X levels, forward and backward, {ISO_RUNS} runs")


def run(args: argparse.Namespace) -> int:
    import sys

    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.errors import InputError

    if args.intrinsics_views:
        if not args.out:
            raise InputError("--intrinsics-views: give --out FOLDER for the images")
        return _intrinsics_mode(args)
    if bool(args.out) == bool(args.resume):
        raise InputError("give either --out SESSION (new capture) or --resume SESSION")
    from lps_gui.capture.setup import apply_setup
    from lps_gui.cli.capture.setup import setup_meta

    extra = setup_meta(args)  # --spec, environment, identification: checked before any device opens
    from lps_gui.cli.capture.live import report_path

    if args.report:
        report_path(args, ".")  # a --report name that cannot be written is refused before the capture
    settle = settle_options(args)
    if args.compensation:
        from lps_gui.io.compensation_file import read_table

        read_table(args.compensation)  # a bad table fails before a session is created
    session, stage, camera, engine = _resume(args) if args.resume else _start(args)
    apply_setup(session, extra)
    try:
        from lps_gui.capture.compensated import apply_compensation

        apply_compensation(engine, session, args.compensation)
        engine.configure_settle(settle)
        if session.plan().segments:  # one board moved between segments: the operator answers at each pause
            from lps_gui.cli.capture.segments import operator_moves_board

            engine.subscribe(operator_moves_board(engine))
        from lps_gui.cli.capture.live import finish_live, start_live

        live = start_live(args, engine)
        print(f"capturing into {session.folder}: {describe(session.plan())}", file=sys.stderr)
        summary = engine.run(progress=ProgressBar("capture"))
    finally:
        close(stage, camera)
    if summary.state == "done":
        print(f"{summary.folder}: {summary.listed}/{summary.total} frames listed ({summary.captured} now)")
        finish_live(args, live, summary)
        return 0
    finish_live(args, live, summary)
    print(
        f"lps capture: {summary.state}: {summary.error or 'stopped'}; {summary.listed}/{summary.total} frames kept, "
        f"continue with `lps capture --resume {summary.folder}{_resume_devices_hint(session)}`",
        file=sys.stderr,
    )
    return 3


def settle_options(args: argparse.Namespace):
    """The --settle-* and --average-frames switches (checked: a bad value is one line before any move)."""
    from lps_gui.capture.settle import SettleOptions

    return SettleOptions(settle_px=args.settle_px, timeout_s=args.settle_timeout_s, average=args.average_frames,
                         agree_frames=args.settle_frames)


def _resume_devices_hint(session) -> str:
    """The device switches a resume of a real-device session needs (never read back by itself)."""
    if (session.truth or {}).get("simulated"):
        import shlex

        from lps_gui.cli.capture.resume_devices import SIMULATED_STAGES

        stage = (session.meta.get("stage") or {}).get("spec")
        return "" if stage in (None, *SIMULATED_STAGES) else f" --stage {shlex.quote(stage)}"  # the rig rode that stage
    stage, camera = (session.meta.get("stage") or {}).get("spec"), (session.meta.get("camera") or {}).get("spec")
    cti = (session.meta.get("camera") or {}).get("cti")  # a GenICam camera's producer
    return (f" --stage {stage} --camera {camera}" + (f" --cti {cti}" if cti else "")) if stage and camera \
        else " --stage ... --camera ..."


def _intrinsics_mode(args: argparse.Namespace) -> int:
    """Guide the operator through varied poses of a hand-held board; Enter takes, s skips, f forces, q quits."""
    import sys
    from pathlib import Path

    from lps_gui.capture.intrinsics_plan import IntrinsicsCapture, intrinsics_plan
    from lps_gui.errors import InputError
    from lps_gui.io.board_file import read_board, write_board

    goals = intrinsics_plan(args.intrinsics_views)
    simulated = (args.camera or "sim") == "sim"
    if simulated:
        from lps_gui.capture.handheld_sim import HandHeldBoardCamera
        from lps_gui.core.truth.simulate import preset

        rig = preset(args.preset).rig
        board = rig.board
        holder: dict = {}
        camera = HandHeldBoardCamera(board, rig.intrinsics, lambda: holder["cap"].current(), noise_grey=args.noise_grey, seed=args.seed)
        camera.open()
    else:
        if not args.board:
            raise InputError("--board FILE is required with a real camera (board.json is described in docs/capture.md)")
        from lps_gui.camera import open_camera
        board = read_board(args.board)
        camera = open_camera(args.camera, **({"cti": args.cti} if args.cti else {}))
    try:
        cap = IntrinsicsCapture(camera, args.out, board, goals)
        if simulated:
            holder["cap"] = cap
        write_board(Path(args.out) / "board.json", board)
        while (goal := cap.current()) is not None:
            print(f"[{goals.index(goal) + 1}/{len(goals)}] {goal.instruction}", file=sys.stderr)
            force = False
            if not simulated:
                print("  Enter: take, s: skip, f: take even if off target, q: quit", file=sys.stderr)
                answer = sys.stdin.readline()
                if answer == "" or answer.strip().lower() == "q":
                    break
                if answer.strip().lower() == "s":
                    cap.skip()
                    continue
                force = answer.strip().lower() == "f"
            result = cap.take(force=force)
            print(f"  {result.message}", file=sys.stderr)
            if simulated and cap.current() == goal:  # the simulated hand missed: move on
                cap.skip()
    finally:
        camera.close()
    taken = sum(1 for d in cap.taken.values() if d.get("file"))
    if not cap.done:
        print(f"lps capture: stopped with {taken} views in {args.out}; run the same command again to continue", file=sys.stderr)
        return 3
    print(f"{args.out}: {taken} views; next: lps intrinsics {args.out} --board {Path(args.out) / 'board.json'}")
    return 0


def _start(args: argparse.Namespace):
    """(session, stage, camera, engine) of a new capture on one axis or, with a planar switch, on two."""
    from lps_gui.errors import InputError

    if args.scene:  # a light-field scene at a measured session's stops (issue 38)
        from lps_gui.cli.capture.scene import start_scene

        return start_scene(args)
    planar = wants_planar(args)
    if planar and args.compensation:
        raise InputError("--compensation: a table corrects one axis; planar plans are captured without one")
    if planar and args.test:
        raise InputError("--test: the ASME B5.64 tests are single-axis tests; drop the planar switches")
    if planar and args.iso_plan:
        raise InputError("--iso-plan is the single-axis ISO 230-2 preset; a planar plan takes --iso-lines")
    stage_spec, camera_spec = args.stage or "sim", args.camera or "sim"
    intr = None if planar else read_intrinsics(args.intrinsics)
    preflight(args, stage_spec, camera_spec)  # everything checkable before anything is created
    axes = {"axes": ["X", "Y"]} if planar else {}
    if camera_spec == "sim":
        from lps_gui.core.truth.simulate import PLANAR_PRESETS, preset
        from lps_gui.sim.rig import check_board_in_view, spec_for_plan
        from lps_gui.sim.session import create_simulated_session, simulated_engine

        if args.board:
            raise InputError(f"--board: the simulated {'gantry' if planar else 'rig'}'s board comes from --preset; "
                             "drop --board")
        if planar:
            if stage_spec not in ("sim", "emulator"):  # a followed stage moves one axis at a time
                raise InputError(f"--stage {stage_spec}: the simulated gantry rides only --stage sim or emulator")
            make_spec = PLANAR_PRESETS[planar_preset_name(args.preset)]
            spec = make_spec(seed=args.seed, plan=build_planar_plan(args, make_spec(seed=args.seed).plan))  # centred
            check_board_in_view(spec)
            intr = read_intrinsics(args.intrinsics)
        else:
            spec = spec_for_plan(args.preset, line_plan(args, preset(args.preset).plan), seed=args.seed)
        from lps_gui.cli.capture.asme_test import simulated_rig_options, simulated_stage

        spec, ringing = simulated_stage(args, spec)  # --dead-band-um, --ringing (a settling test rings by default)
        driver = None if stage_spec in ("sim", "emulator") else open_operator_stage(stage_spec)  # fails before the session
        try:
            session, stage, camera = create_simulated_session(args.out, spec, clock=clock(args), noise_grey=args.noise_grey,
                                                              intrinsics=intr, **simulated_rig_options(ringing))
            stage = bind_simulated_stage(args, session, stage, camera, stage_spec, driver=driver, **axes)
        except BaseException:
            if driver is not None:
                driver.disconnect()
            raise
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    if not args.board:
        raise InputError("--board FILE is required with a real camera (board.json is described in docs/capture.md)")
    from lps_gui.io.board_file import read_board

    if planar:
        plan = build_planar_plan(args)
        board, intr = read_board(args.board), read_intrinsics(args.intrinsics)
    else:
        board = read_board(args.board)
        plan = line_plan(args)
    return device_session(args, board, plan, intr, stage_spec, camera_spec, **axes)


def _resume(args: argparse.Namespace):
    """(session, stage, camera, engine) going on with a session: on the rebuilt simulated rig (or gantry),
    or on the devices the operator names."""
    from lps_gui.capture.engine import CaptureEngine
    from lps_gui.errors import InputError
    from lps_gui.io.session import Session

    session = Session.open(args.resume)
    if (session.meta.get("stage") or {}).get("driver") == "import":  # SPEC 16: no stage and no plan to go on with
        raise InputError(f"{session.folder}: imported images (lps import), not a capture; nothing to resume: import "
                         "the whole folder again into a new session")
    if session.planar:
        given = [s for s, v in (("--grid", args.grid), ("--targets-xy", args.targets_xy), ("--iso-lines", args.iso_lines),
                                ("--pattern", args.pattern), ("--plan", args.plan)) if v]
        if given:
            raise InputError(f"{' '.join(given)}: a resumed session keeps its own plan; drop {given[0]}")
    elif wants_planar(args):
        raise InputError(f"{session.folder}: a single-axis session; resume it without the planar switches")
    truth = session.truth or {}
    if truth.get("simulated") and (args.camera or "sim") == "sim":
        from lps_gui.cli.capture.resume_devices import rig_stage_named_by_operator
        from lps_gui.sim.session import reopen_simulated_rig, simulated_engine

        stage_spec = rig_stage_named_by_operator(session, args.stage)
        stage, camera = reopen_simulated_rig(session, clock=clock(args))
        stage = bind_stage(stage_spec, stage, args.time_scale, args)
        if "spec" not in (session.meta.get("stage") or {}) or "spec" not in (session.meta.get("camera") or {}):
            # a kill between the start's two session.json writes left the devices unrecorded: record them now
            axes = {"axes": ["X", "Y"]} if session.planar else {}
            from lps_gui.capture.setup import device_records

            session.meta["stage"], session.meta["camera"] = device_records(stage, camera, stage_spec, "sim", **axes)
            session.save_meta()
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    from lps_gui.cli.capture.resume_devices import devices_named_by_operator

    stage_spec, camera_spec = devices_named_by_operator(session, args.stage, args.camera)
    stage, camera = open_devices(stage_spec, camera_spec, getattr(args, "cti", None))
    try:
        release_lock(args, stage)
    except BaseException:
        close(stage, camera)
        raise
    return session, stage, camera, CaptureEngine(stage, camera, session, encode=args.encode)
