"""A simulated capture through each vendor's library and emulator (Zaber, Thorlabs) against the direct one:
the same stops, the same truth, and a port lost mid-run pauses the capture, which a new connection finishes."""
from __future__ import annotations

import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.hardware.thorlabs_emulator import emulated_thorlabs_stage
from lps_gui.hardware.zaber_emulator import emulated_zaber_stage
from lps_gui.io.session import Session
from lps_gui.sim.session import create_simulated_session, simulated_engine
from tests.capture.helpers import (
    assert_listed_frames_intact,
    image_bytes,
    records_without_time,
    start_capture,
    tiny_spec,
)

# stops each device reaches exactly: whole microsteps for Zaber (3.048 mm = 64000 of 0.047625 um), whole encoder
# counts for Thorlabs (1 mm = 34304)
PLANS = {
    "zaber": Plan(start_mm=3.048, stop_mm=9.144, step_mm=3.048, directions="both", overshoot_mm=3.048, settle_s=0.0,
                  feed_mm_min=1200.0),
    "thorlabs": Plan(start_mm=2.0, stop_mm=6.0, step_mm=2.0, directions="both", overshoot_mm=1.0, settle_s=0.0,
                     feed_mm_min=1200.0),
}
KINDS = {"zaber": emulated_zaber_stage, "thorlabs": emulated_thorlabs_stage}


def direct_capture(folder, plan: Plan) -> Session:
    session, *_, engine = start_capture(folder, plan=plan)
    assert engine.run().state == "done"
    return session


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_capture_through_the_vendor_library_equals_direct_capture(tmp_path, kind):
    direct = direct_capture(tmp_path / "direct", PLANS[kind])
    session, rig_stage, camera = create_simulated_session(tmp_path / kind, tiny_spec(PLANS[kind]))
    stage = KINDS[kind](time_scale=50.0, simulated=rig_stage)
    try:
        summary = simulated_engine(session, stage, camera).run()
    finally:
        stage.disconnect()
    assert summary.state == "done", summary.error
    assert_listed_frames_intact(session)
    assert records_without_time(session) == records_without_time(direct)  # identical stops, targets, reports
    assert image_bytes(session) == image_bytes(direct)
    assert Session.open(session.folder).truth["axis_mm"] == Session.open(direct.folder).truth["axis_mm"]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_port_lost_mid_capture_pauses_and_a_new_connection_finishes(tmp_path, kind):
    plan = PLANS[kind]
    direct = direct_capture(tmp_path / "direct", plan)
    session, rig_stage, camera = create_simulated_session(tmp_path / kind, tiny_spec(plan))
    stage = KINDS[kind](time_scale=50.0, simulated=rig_stage)
    moves = []

    def unplug_on_third_move(data: bytes) -> bool:  # the cable goes at the third absolute move
        moves.append(b"move abs" in data or b"\x53\x04\x06\x00" in data)  # MOT_MOVE_ABSOLUTE, 6 data bytes
        return sum(moves) >= 3

    stage.emulator.drop_when = unplug_on_third_move
    try:
        first = simulated_engine(session, stage, camera).run()
    finally:
        stage.disconnect()
    assert first.state == "paused" and 0 < first.listed < 6, first
    assert "\n" not in first.error and "vanished" in first.error, first.error
    assert_listed_frames_intact(session)

    stage = KINDS[kind](time_scale=50.0, simulated=rig_stage)  # plugged in again; the engine resumes the session
    try:
        second = simulated_engine(Session.open(session.folder), stage, camera).run()
    finally:
        stage.disconnect()
    assert second.state == "done" and second.listed == 6
    assert records_without_time(session) == records_without_time(direct)
    assert image_bytes(session) == image_bytes(direct)
