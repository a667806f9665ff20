"""`lps capture`: run a capture plan on a stage and a camera into a session folder; resume after any stop.

Examples::

    lps capture --out run1                                   # simulated rig, preset "small"
    lps capture --preset paper-rig --directions both --runs 2 --out run2
    lps capture --stage grbl:/dev/ttyUSB0 --camera 0 --plan plan.json \\
                --board board.json --intrinsics intrinsics.json --out run3
    lps capture --resume run3 [--stage grbl:/dev/ttyUSB0 --camera 0]
    lps capture --intrinsics-views 15 --camera 0 --board board.json --out intr   # hand-held board, guided
"""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import finite, float_range, int_range, nonnegative_finite, nonnegative_int, positive_finite

from lps_gui.cli import planar_capture

HELP = "capture a session: move the stage through a plan and store an image per stop (resumable)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--stage", default=None, help="sim | emulator | grbl:PORT (default sim)")
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
    from lps_gui.cli.capture_setup import add_setup_arguments

    add_setup_arguments(p)
    a = p.add_argument_group("settle detection and averaging")
    a.add_argument("--settle-px", type=positive_finite, metavar="PX", help="before each stop's frame, grab until consecutive frames show the "
                   "board within PX pixels (mean corner shift), e.g. 0.02")
    a.add_argument("--settle-timeout-s", type=positive_finite, default=10.0, metavar="S", help="give up settling after S seconds and take the frame (default 10)")
    a.add_argument("--settle-frames", type=int_range(2, 100), default=3, metavar="N", help="N consecutive frames must agree (default 3; 2: one pair)")
    a.add_argument("--average-frames", type=int_range(1, 1000), default=1, metavar="N", help="store the pixel mean of N frames per image (noise / sqrt(N))")
    s.add_argument("--compensation", metavar="FILE", help="command each target through this table's inverse (lps compensate --format csv|linuxcnc|linuxcnc-offsets)")
    planar_capture.add_arguments(p)


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
    from lps_gui.cli.capture_setup import apply_setup, setup_meta

    extra = setup_meta(args)  # --spec, environment, identification: checked before any device opens
    settle = settle_options(args)
    if args.compensation:
        from lps_gui.io.compensation_file import read_table

        read_table(args.compensation)  # a bad table fails before a session is created
    opened = planar_capture.open_planar_capture(args)  # None: a single-axis capture
    session, stage, camera, engine = opened or (_resume(args) if args.resume else _start(args))
    apply_setup(session, extra)
    try:
        from lps_gui.capture.compensated import apply_compensation

        apply_compensation(engine, session, args.compensation)
        engine.configure_settle(settle)
        print(f"capturing into {session.folder}: {_describe(session)}", file=sys.stderr)
        summary = engine.run(progress=ProgressBar("capture"))
    finally:
        _close(stage, camera)
    if summary.state == "done":
        print(f"{summary.folder}: {summary.listed}/{summary.total} frames listed ({summary.captured} now)")
        return 0
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
        return ""
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
        from lps_gui.core.simulate import preset

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


def _describe(session) -> str:
    from lps_gui.capture.plans import describe_plan, plan_duration_s

    plan = session.plan()
    if session.planar:
        return planar_capture.describe_planar(plan)
    return f"{describe_plan(plan)}, about {plan_duration_s(plan) / 60:.1f} min of stage time"


def _plan(args: argparse.Namespace, base=None):
    from lps_gui.capture.plans import parse_targets, plan_with, read_plan

    if args.plan:
        base = read_plan(args.plan)
    fields = {k: getattr(args, k) for k in ("start_mm", "stop_mm", "step_mm", "directions", "runs", "overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min")}
    if args.targets:
        fields["targets_mm"] = parse_targets(args.targets)
    from lps_gui.cli.capture_setup import iso_plan_fields

    fields.update(iso_plan_fields(args, base))
    if base is None and not any(fields[k] is not None for k in ("start_mm", "stop_mm", "step_mm", "targets_mm") if k in fields):
        from lps_gui.errors import InputError

        raise InputError("no plan: give --plan FILE or --start/--stop/--step (or --targets)")
    return plan_with(base, **fields)


def _start(args: argparse.Namespace):
    from lps_gui.errors import InputError

    stage_spec, camera_spec = args.stage or "sim", args.camera or "sim"
    intr = _read_intrinsics(args.intrinsics)
    _preflight(args, stage_spec, camera_spec)  # everything checkable before anything is created
    if camera_spec == "sim":
        from lps_gui.sim.rig import spec_for_plan
        from lps_gui.sim.session import create_simulated_session, simulated_engine
        from lps_gui.core.simulate import preset

        if args.board:
            raise InputError("--board: the simulated rig's board comes from --preset; drop --board")
        base = preset(args.preset).plan
        spec = spec_for_plan(args.preset, _plan(args, base), seed=args.seed)
        session, stage, camera = create_simulated_session(args.out, spec, clock=_clock(args), noise_grey=args.noise_grey, intrinsics=intr)
        stage = bind_simulated_stage(args, session, stage, camera, stage_spec)
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    if not args.board:
        raise InputError("--board FILE is required with a real camera (board.json is described in docs/capture.md)")
    from lps_gui.io.board_file import read_board

    return device_session(args, read_board(args.board), _plan(args), intr, stage_spec, camera_spec)


def device_session(args: argparse.Namespace, board, plan, intr, stage_spec: str, camera_spec: str, **stage_meta):
    """Open the operator's devices, unlock as asked and create the session on them (devices closed on failure)."""
    from lps_gui.capture.engine import CaptureEngine
    from lps_gui.io.session import Session

    stage, camera = _open_devices(stage_spec, camera_spec, getattr(args, "cti", None))
    try:
        _release_lock(args, stage)
        session = Session.create(
            args.out, board, plan, intr,
            camera={**camera.properties(), "spec": camera_spec},
            stage={**stage.describe(), **stage_meta, "spec": stage_spec},
            extra={"intrinsics_source": str(args.intrinsics)} if args.intrinsics else None,
        )
    except BaseException:
        _close(stage, camera)
        raise
    return session, stage, camera, CaptureEngine(stage, camera, session, encode=args.encode)


def _resume(args: argparse.Namespace):
    from lps_gui.capture.engine import CaptureEngine
    from lps_gui.io.session import Session

    session = Session.open(args.resume)
    truth = session.truth or {}
    if truth.get("simulated") and (args.camera or "sim") == "sim":
        from lps_gui.sim.session import reopen_simulated_rig, simulated_engine

        stage, camera = reopen_simulated_rig(session, clock=_clock(args))
        stage = _bind_stage(args.stage or "sim", stage, args.time_scale)
        if "spec" not in (session.meta.get("stage") or {}) or "spec" not in (session.meta.get("camera") or {}):
            # a kill between the start's two session.json writes left the devices unrecorded: record them now
            session.meta["stage"] = {**stage.describe(), "spec": args.stage or "sim"}
            session.meta["camera"] = {**camera.properties(), "spec": "sim"}
            session.save_meta()
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    from lps_gui.cli.resume_devices import devices_named_by_operator

    stage_spec, camera_spec = devices_named_by_operator(session, args.stage, args.camera)
    stage, camera = _open_devices(stage_spec, camera_spec, getattr(args, "cti", None))
    try:
        _release_lock(args, stage)
    except BaseException:
        _close(stage, camera)
        raise
    return session, stage, camera, CaptureEngine(stage, camera, session, encode=args.encode)


def _preflight(args: argparse.Namespace, stage_spec: str, camera_spec: str) -> None:
    from lps_gui.cli.capture_preflight import check_capture_args

    check_capture_args(args, stage_spec, camera_spec)


def _release_lock(args: argparse.Namespace, stage) -> None:
    import sys

    from lps_gui.capture.stage_lock import release_lock

    done = release_lock(stage, "home" if args.home else "unlock" if args.unlock else None)
    if done:
        print(f"lps capture: the stage was locked in Alarm; {done} it", file=sys.stderr)


def _open_devices(stage_spec: str, camera_spec: str, cti: str | None = None):
    from lps_gui.camera import open_camera
    from lps_gui.errors import InputError
    from lps_gui.hardware import open_stage

    if camera_spec == "sim":
        raise InputError("--camera sim follows only the simulated rig; use --stage sim or emulator")
    stage = open_stage(stage_spec)
    try:
        camera = open_camera(camera_spec, **({"cti": cti} if cti else {}))
    except BaseException:
        stage.disconnect()
        raise
    return stage, camera


def bind_simulated_stage(args: argparse.Namespace, session, rig_stage, camera, stage_spec: str, **stage_meta):
    """The simulated rig's stage as the command line asked for it (direct or through the emulator), unlocked
    as asked, and recorded in session.json with the camera and the intrinsics' source."""
    stage = _bind_stage(stage_spec, rig_stage, args.time_scale)
    _release_lock(args, stage)
    session.meta["stage"] = {**stage.describe(), **stage_meta, "spec": stage_spec}
    session.meta["camera"] = {**camera.properties(), "spec": "sim"}
    if args.intrinsics:
        session.meta["intrinsics_source"] = str(args.intrinsics)
    session.save_meta()
    return stage


def _bind_stage(stage_spec: str, rig_stage, time_scale: float = 1.0):
    """Connect the simulated rig's stage directly ("sim") or through the GRBL emulator ("emulator")."""
    from lps_gui.errors import InputError

    if stage_spec == "sim":
        rig_stage.connect()
        return rig_stage
    if stage_spec == "emulator":
        from lps_gui.sim.emulated import emulated_rig_stage

        return emulated_rig_stage(rig_stage, time_scale=time_scale)
    raise InputError(f"--stage {stage_spec}: the simulated camera rides only --stage sim or emulator")


def _clock(args: argparse.Namespace):
    from lps_gui.core.clock import RealClock, SimClock

    return RealClock() if args.real_time else SimClock()


def _read_intrinsics(path: str | None):
    if not path:
        return None
    from lps_gui.io.intrinsics_file import read_intrinsics

    return read_intrinsics(path)


def _close(stage, camera) -> None:
    for fn in (camera.close, stage.disconnect):
        try:
            fn()
        except Exception:  # closing a vanished device must not hide the capture's own result
            pass
