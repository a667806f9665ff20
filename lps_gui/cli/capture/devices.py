"""The devices of `lps capture`: the operator's stage and camera, or the simulated rig's, bound, unlocked and closed.

Shared by a capture on one axis and on two (SPEC 10): the session records
what was bound (``stage.spec``, ``camera.spec``), so a resume can name them.
"""
from __future__ import annotations

import argparse


def clock(args: argparse.Namespace):
    """The simulated rig's clock: real time with --real-time, else simulated."""
    from lps_gui.core.clock import RealClock, SimClock

    return RealClock() if args.real_time else SimClock()


def read_intrinsics(path: str | None):
    """The --intrinsics file, read before anything is created (None: not given)."""
    if not path:
        return None
    from lps_gui.io import intrinsics_file
    return intrinsics_file.read_intrinsics(path)


def preflight(args: argparse.Namespace, stage_spec: str, camera_spec: str) -> None:
    """Everything checkable before anything is created: the stage against the camera, the image format."""
    from lps_gui.cli.capture.preflight import check_capture_args

    check_capture_args(args, stage_spec, camera_spec)


def device_session(args: argparse.Namespace, board, plan, intr, stage_spec: str, camera_spec: str, **stage_meta):
    """Open the operator's devices, unlock as asked and create the session on them (devices closed on failure)."""
    from lps_gui.capture.engine import CaptureEngine
    from lps_gui.capture.setup import device_records
    from lps_gui.io.session import Session

    stage, camera = open_devices(stage_spec, camera_spec, getattr(args, "cti", None))
    try:
        release_lock(args, stage)
        stage_record, camera_record = device_records(stage, camera, stage_spec, camera_spec, **stage_meta)
        session = Session.create(args.out, board, plan, intr, camera=camera_record, stage=stage_record,
                                 extra={"intrinsics_source": str(args.intrinsics)} if args.intrinsics else None)
    except BaseException:
        close(stage, camera)
        raise
    return session, stage, camera, CaptureEngine(stage, camera, session, encode=args.encode)


def release_lock(args: argparse.Namespace, stage) -> None:
    """Home (--home) or unlock (--unlock) a stage locked in Alarm."""
    import sys

    from lps_gui.capture.stage_lock import release_lock

    done = release_lock(stage, "home" if args.home else "unlock" if args.unlock else None)
    if done:
        print(f"lps capture: the stage was locked in Alarm; {done} it", file=sys.stderr)


def open_devices(stage_spec: str, camera_spec: str, cti: str | None = None):
    """The operator's stage and camera (the stage closed again when the camera fails to open)."""
    from lps_gui.camera import open_camera
    from lps_gui.errors import InputError
    if camera_spec == "sim":
        raise InputError("--camera sim follows only the simulated rig; use --stage sim or emulator")
    stage = open_operator_stage(stage_spec)
    try:
        camera = open_camera(camera_spec, **({"cti": cti} if cti else {}))
    except BaseException:
        stage.disconnect()
        raise
    return stage, camera


def open_operator_stage(stage_spec: str):
    """The stage ``stage_spec`` names, connected; one the operator moves by hand asks on this terminal."""
    from lps_gui.hardware import open_stage
    from lps_gui.hardware.capabilities import OperatorMoved

    stage = open_stage(stage_spec)
    if isinstance(stage, OperatorMoved):
        from lps_gui.hardware.manual import terminal_prompt

        stage.attach_prompt(terminal_prompt)
    return stage


def bind_simulated_stage(args: argparse.Namespace, session, rig_stage, camera, stage_spec: str, driver=None, **stage_meta):
    """The simulated rig's stage as the command line asked for it (direct or through the emulator), unlocked
    as asked, and recorded in session.json with the camera and the intrinsics' source."""
    from lps_gui.capture.setup import device_records

    stage = bind_stage(stage_spec, rig_stage, args.time_scale, args, driver)
    session.meta["stage"], session.meta["camera"] = device_records(stage, camera, stage_spec, "sim", **stage_meta)
    if args.intrinsics:
        session.meta["intrinsics_source"] = str(args.intrinsics)
    session.save_meta()
    return stage


def bind_stage(stage_spec: str, rig_stage, time_scale: float = 1.0, args: argparse.Namespace | None = None, driver=None):
    """Connect the simulated rig's stage directly ("sim"), through the GRBL emulator ("emulator"), or behind
    any other stage, which it follows move by move (:class:`~lps_gui.sim.follow.FollowedStage`); unlocked
    as ``args`` ask (--home, --unlock). ``driver``: that other stage, already opened."""
    if stage_spec == "sim":
        rig_stage.connect()
        stage = rig_stage
    elif stage_spec == "emulator":
        from lps_gui.sim.emulated import emulated_rig_stage

        stage = emulated_rig_stage(rig_stage, time_scale=time_scale)
    else:
        from lps_gui.sim.follow import FollowedStage

        driver = driver or open_operator_stage(stage_spec)
        try:
            if args is not None:
                release_lock(args, driver)
            rig_stage.connect()
        except BaseException:
            driver.disconnect()
            raise
        return FollowedStage(driver, rig_stage)
    if args is not None:
        release_lock(args, stage)
    return stage


def close(stage, camera) -> None:
    """Close the camera and disconnect the stage, whatever state they are in."""
    for fn in (camera.close, stage.disconnect):
        try:
            fn()
        except Exception:  # closing a vanished device must not hide the capture's own result
            pass
