"""`lps capture --scene MEASURED_SESSION --out DIR`: the measured session's plan again, without the board.

Same stops and approach direction as the measurement's first pass (optionally through its compensation
table, ``--compensation FILE``, so the views land on the nominal grid); on the simulated rig the board is
replaced by the light-field scene, on real devices the operator takes the board away. The new session
names the measurement it relies on (``lps lightfield`` reads positions and rotations from there).
"""
from __future__ import annotations

import argparse


def add_scene_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scene", metavar="MEASURED_SESSION",
                   help="capture a light-field scene (no board) at the stops of this measured session's first pass "
                        "into --out; then `lps lightfield --out DIR SCENE_SESSION`")


def start_scene(args: argparse.Namespace):
    """(session, stage, camera, engine) of a scene capture on the measurement's rig or the operator's devices."""
    from lps_gui.cli.capture.devices import bind_simulated_stage, clock, device_session, preflight
    from lps_gui.errors import InputError
    from lps_gui.io.scene_link import SCENE_KEY, measurement_link
    from lps_gui.io.session import Session
    from lps_gui.sim.scene_session import scene_plan

    given = [s for s, v in (("--plan", args.plan), ("--start", args.start_mm), ("--stop", args.stop_mm),
                            ("--step", args.step_mm), ("--targets", args.targets), ("--directions", args.directions),
                            ("--runs", args.runs), ("--grid", args.grid), ("--targets-xy", args.targets_xy),
                            ("--board", args.board)) if v]
    if given:
        raise InputError(f"{given[0]}: a scene capture repeats the measured session's plan; drop {given[0]}")
    measured = Session.open(args.scene)
    if measured.planar and args.compensation:
        raise InputError("--compensation: a table corrects one axis; planar scenes are captured without one")
    stage_spec, camera_spec = args.stage or "sim", args.camera or "sim"
    preflight(args, stage_spec, camera_spec)
    axes = {"axes": ["X", "Y"]} if measured.planar else {}
    if camera_spec == "sim":
        from lps_gui.sim.scene_session import create_scene_session
        from lps_gui.sim.session import simulated_engine

        session, stage, camera = create_scene_session(args.out, measured, clock=clock(args), noise_grey=args.noise_grey)
        stage = bind_simulated_stage(args, session, stage, camera, stage_spec, **axes)
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    link = measurement_link(measured)
    session, stage, camera, engine = device_session(args, measured.targets() or measured.board(),
                                                    scene_plan(measured.plan()), measured.intrinsics(),
                                                    stage_spec, camera_spec, **axes)
    session.meta[SCENE_KEY] = {"measurement_session": link}
    session.save_meta()
    return session, stage, camera, engine
