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
    from lps_gui.cli.capture_preflight import check_capture_args

    check_capture_args(args, stage_spec, camera_spec)


def device_session(args: argparse.Namespace, board, plan, intr, stage_spec: str, camera_spec: str, **stage_meta):
    """Open the operator's devices, unlock as asked and create the session on them (devices closed on failure)."""
    from lps_gui.capture.engine import CaptureEngine
    from lps_gui.io.session import Session

    stage, camera = open_devices(stage_spec, camera_spec, getattr(args, "cti", None))
    try:
        release_lock(args, stage)
        session = Session.create(
            args.out, board, plan, intr,
            camera={**camera.properties(), "spec": camera_spec},
            stage={**stage.describe(), **stage_meta, "spec": stage_spec},
            extra={"intrinsics_source": str(args.intrinsics)} if args.intrinsics else None,
        )
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


def bind_simulated_stage(args: argparse.Namespace, session, rig_stage, camera, stage_spec: str, real=None,
                         **stage_meta):
    """The simulated rig's stage as the command line asked for it (direct or through the emulator), unlocked
    as asked, and recorded in session.json with the camera and the intrinsics' source.

    ``real``: a stage already opened for ``grbl:PORT`` (:func:`open_followed_stage`); the camera follows it."""
    stage = bind_stage(stage_spec, rig_stage, args.time_scale) if real is None else real
    release_lock(args, stage)
    session.meta["stage"] = {**stage.describe(), **stage_meta, "spec": stage_spec}
    session.meta["camera"] = {**camera.properties(), "spec": "sim"}
    if args.intrinsics:
        session.meta["intrinsics_source"] = str(args.intrinsics)
    session.save_meta()
    return stage


def open_followed_stage(stage_spec: str, camera=None):
    """The ``grbl:PORT`` stage the simulated camera follows (its reported position), or None for sim/emulator.

    Opened before the session is created: a port that cannot open leaves nothing behind.
    """
    if not stage_spec.startswith("grbl:"):
        return None
    from lps_gui.hardware import open_stage

    stage = open_stage(stage_spec)
    if camera is not None:
        follow(camera, stage)
    return stage


def follow(camera, stage) -> None:
    from lps_gui.sim.follow_stage import follow_reported_position

    follow_reported_position(camera, stage)


def bind_stage(stage_spec: str, rig_stage, time_scale: float = 1.0):
    """Connect the simulated rig's stage directly ("sim") or through the GRBL emulator ("emulator")."""
    from lps_gui.errors import InputError

    if stage_spec == "sim":
        rig_stage.connect()
        return rig_stage
    if stage_spec == "emulator":
        from lps_gui.sim.emulated import emulated_rig_stage

        return emulated_rig_stage(rig_stage, time_scale=time_scale)
    raise InputError(f"--stage {stage_spec}: the simulated camera rides --stage sim, emulator or grbl:PORT")


def close(stage, camera) -> None:
    """Close the camera and disconnect the stage, whatever state they are in."""
    for fn in (camera.close, stage.disconnect):
        try:
            fn()
        except Exception:  # closing a vanished device must not hide the capture's own result
            pass
