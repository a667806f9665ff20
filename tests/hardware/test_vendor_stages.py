"""One contract for the stages driven through a vendor's library (Zaber, Thorlabs), each against its emulator:
moves land on whole device units, a hold stops and resume finishes, a lost port is one line."""
from __future__ import annotations

import pytest

from lps_gui.errors import HardwareError, LpsError
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.thorlabs import ThorlabsStage
from lps_gui.hardware.thorlabs_emulator import ThorlabsEmulator
from lps_gui.hardware.zaber import ZaberStage
from lps_gui.hardware.zaber_emulator import ZaberEmulator

TRAVEL = (0.0, 100.0)
KINDS = {  # emulator, driver, the device's position unit in mm (its documented scale)
    "zaber": (ZaberEmulator, lambda path: ZaberStage(path, poll_interval_s=0.002), 3.048 / 64 / 1000.0),
    "thorlabs": (ThorlabsEmulator, ThorlabsStage, 1 / 34304),
}


@pytest.fixture(params=sorted(KINDS))
def rig(request):
    emulator_cls, driver, unit_mm = KINDS[request.param]
    with emulator_cls(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), time_scale=200.0) as emu:
        stage = driver(emu.path)
        stage.connect()
        yield emu, stage, unit_mm
        stage.disconnect()


def test_move_lands_on_whole_device_units_where_the_simulated_carriage_is(rig):
    emu, stage, unit = rig
    stage.move_to(42.5, 3000.0)
    st = stage.wait_idle(timeout_s=30.0)
    assert st.idle and st.work_mm[0] == pytest.approx(round(42.5 / unit) * unit, abs=1e-12)
    assert emu.stage.status().work_mm[0] == pytest.approx(st.work_mm[0], abs=1e-12)
    assert abs(stage.position_mm() - 42.5) <= unit / 2


def test_home_then_move(rig):
    emu, stage, unit = rig
    stage.home()
    assert stage.position_mm() == 0.0  # homing resets the position to 0 at the home switch (both manuals)
    home_mm = emu.stage.status().work_mm[0]
    assert home_mm == pytest.approx(TRAVEL[0] + 1.0)  # the simulated stage's switch + pull-off
    stage.move_to(20.0, 6000.0)
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(round(20.0 / unit) * unit, abs=1e-12)
    assert emu.stage.status().work_mm[0] == pytest.approx(home_mm + round(20.0 / unit) * unit, abs=1e-12)


def test_hold_then_resume_reaches_the_target(rig):
    emu, stage, unit = rig
    emu.time_scale = 1.0  # slow enough to stop before the end
    stage.move_to(90.0, 600.0)
    stage.feed_hold()
    with pytest.raises(HardwareError, match="Hold"):
        stage.wait_idle(timeout_s=5.0)
    emu.time_scale = 200.0
    stage.resume()
    assert stage.wait_idle(timeout_s=30.0).work_mm[0] == pytest.approx(round(90.0 / unit) * unit, abs=1e-12)


def test_port_vanishing_mid_move_is_one_line_error(rig):
    emu, stage, unit = rig
    emu.time_scale = 1.0
    stage.move_to(90.0, 300.0)
    emu.drop()
    with pytest.raises(LpsError) as e:
        stage.wait_idle(timeout_s=10.0)
    text = str(e.value)
    assert "\n" not in text and "vanished" in text and "reconnect" in text
    with pytest.raises(LpsError, match="vanished"):  # and every later call says the same
        stage.status()
    assert not stage.connected


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_drop_after_fault_of_lps_emulate_unplugs_the_cable(kind):
    """`lps emulate KIND --drop-after-lines N` builds the emulator with the GRBL fault switches; these
    controllers honour the cable drop (after N commands received) and ignore the rest."""
    from lps_gui.hardware.grbl.firmware import Faults

    emulator_cls, driver, unit_mm = KINDS[kind]
    emu = emulator_cls(SimulatedStage(travel_mm=TRAVEL, start_mm=10.0), faults=Faults(drop_after_lines=40),
                       time_scale=1.0)
    with emu:
        stage = driver(emu.path)
        with pytest.raises(LpsError) as e:  # at connect or during the move, wherever the 40th command falls
            stage.connect()
            stage.move_to(90.0, 300.0)
            stage.wait_idle(timeout_s=30.0)
        stage.disconnect()
    assert emu.dropped and "\n" not in str(e.value)


def test_stop_ends_the_move_short_of_the_target(rig):
    emu, stage, unit = rig
    emu.time_scale = 1.0
    stage.move_to(90.0, 600.0)
    stage.stop()
    x = stage.wait_idle(timeout_s=10.0).work_mm[0]
    assert 10.0 <= x < 90.0 and stage.status().idle  # stopped, not held: nothing to resume
