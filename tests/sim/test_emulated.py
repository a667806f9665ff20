"""The simulated rig through the real GRBL driver and the pty emulator gives the same session as the direct one."""
from __future__ import annotations

from lps_gui.core.planning.plan import Plan
from lps_gui.io.session import Session
from lps_gui.sim.emulated import emulated_rig_stage
from lps_gui.sim.session import create_simulated_session, simulated_engine
from tests.capture.helpers import (
    assert_listed_frames_intact,
    capture_through_emulator,
    image_bytes,
    records_without_time,
    start_capture,
    tiny_spec,
)

PLAN = Plan(start_mm=0.0, stop_mm=4.0, step_mm=2.0, directions="both", overshoot_mm=1.0, settle_s=0.0, feed_mm_min=1200.0)


def test_capture_through_grbl_emulator_equals_direct_capture(tmp_path):
    direct, *_, engine = start_capture(tmp_path / "direct", plan=PLAN)
    assert engine.run().state == "done"

    session, _ = capture_through_emulator(tmp_path / "emulated", tiny_spec(PLAN), time_scale=50.0)
    assert_listed_frames_intact(session)
    assert records_without_time(session) == records_without_time(direct)
    assert image_bytes(session) == image_bytes(direct)
    assert Session.open(session.folder).truth["axis_mm"] == Session.open(direct.folder).truth["axis_mm"]
    assert Session.open(session.folder).meta["stage"]["driver"] == "RigStage"  # session.json describes the rig's stage


def test_port_dropped_by_the_grbl_emulator_pauses_then_a_new_connection_resumes(tmp_path):
    """The real driver loses its port mid-run: a clear pause; a new connection (new engine, as --resume) finishes."""
    from lps_gui.hardware.grbl.firmware import Faults

    direct, *_, engine = start_capture(tmp_path / "direct", plan=PLAN)
    assert engine.run().state == "done"

    session, rig_stage, camera = create_simulated_session(tmp_path / "emulated", tiny_spec(PLAN))
    stage = emulated_rig_stage(rig_stage, time_scale=50.0, faults=Faults(drop_after_lines=6))
    try:
        first = simulated_engine(session, stage, camera).run()
    finally:
        stage.disconnect()
    assert first.state == "paused" and first.listed < 6
    assert "port" in first.error.lower() or "disconnect" in first.error.lower() or "vanish" in first.error.lower(), first.error
    assert_listed_frames_intact(session)

    stage = emulated_rig_stage(rig_stage, time_scale=50.0)  # plugged in again
    try:
        second = simulated_engine(Session.open(session.folder), stage, camera).run()
    finally:
        stage.disconnect()
    assert second.state == "done" and second.listed == 6
    assert records_without_time(session) == records_without_time(direct)
    assert image_bytes(session) == image_bytes(direct)
