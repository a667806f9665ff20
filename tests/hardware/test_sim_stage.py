"""SimulatedStage: motion in simulated time, limits, homing, holds, and truth from the shared error model."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.clock import SimClock
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel
from lps_gui.errors import HardwareError
from lps_gui.hardware.machine_settings import NUMBER
from lps_gui.hardware.motion import duration_s, trapezoid
from lps_gui.hardware.refusals import Alarm, Refusal, StageAlarm, StageRefused
from lps_gui.hardware.sim_stage import SimulatedStage


def make(**kw) -> SimulatedStage:
    st = SimulatedStage(**kw)
    st.connect()
    return st


def test_trapezoid_respects_rate_and_acceleration():
    p = trapezoid(0, "Run", 0.0, 0.0, 100.0, 3000.0, 200.0)  # 50 mm/s, 200 mm/s^2
    # ramp 0.25 s over 6.25 mm each end, cruise 87.5 mm at 50 mm/s = 1.75 s
    assert p.t_end == pytest.approx(0.25 + 1.75 + 0.25)
    t = np.linspace(0, p.t_end, 401)
    xv = np.array([p.at(ti) for ti in t])
    assert np.all(np.diff(xv[:, 0]) >= -1e-12)
    assert np.max(np.abs(xv[:, 1])) <= 50.0 + 1e-9
    assert np.max(np.abs(np.diff(xv[:, 1]) / np.diff(t))) <= 200.0 * (1 + 1e-6)
    assert p.at(p.t_end + 1)[0] == 100.0
    short = duration_s(1.0, 3000.0, 200.0)  # triangle: 2*sqrt(d/a)
    assert short == pytest.approx(2 * np.sqrt(1.0 / 200.0))


def test_move_takes_simulated_time_and_no_real_time():
    clock = SimClock()
    st = make(clock=clock)
    st.move_to(100.0, 3000.0)
    assert st.status().state == "Run"
    st2 = st.wait_idle()
    assert st2.state == "Idle"
    assert st2.work_mm[0] == pytest.approx(100.0)
    assert clock.now() == pytest.approx(2.25)


def test_status_mid_move_interpolates_and_reports_feed():
    clock = SimClock()
    st = make(clock=clock)
    st.move_to(100.0, 3000.0)
    clock.advance(1.0)  # 6.25 mm ramp + 0.75 s at 50 mm/s
    s = st.status()
    assert s.work_mm[0] == pytest.approx(6.25 + 37.5)
    assert s.feed_mm_min == pytest.approx(3000.0)
    assert st.planner_free() == 14 and s.buffer is None  # no serial buffer: the GRBL emulator reports Bf (test_grbl_emulator)


def test_queued_moves_run_back_to_back():
    st = make()
    for x in (10.0, 20.0, 5.0):
        st.move_to(x, 1200.0)
    assert st.planner_free() == 12
    assert st.wait_idle().work_mm[0] == pytest.approx(5.0)


def test_true_pose_has_backlash_of_approach_direction_and_repeatability():
    err = StageErrorModel(backlash_um=10.0, scale_ppm=100.0, straightness_um=(ErrorProfile(poly=(1.0,)), ErrorProfile()))
    st = make(errors=err)
    st.move_to(50.0, 3000.0)
    st.wait_idle()
    up = st.true_pose()
    st.move_to(60.0, 3000.0)
    st.move_to(50.0, 3000.0)
    st.wait_idle()
    down = st.true_pose()
    # scale 100 ppm at 50 mm = 5 um; backlash: -5 um moving up, +5 um moving down
    assert up.axis_mm[0] == pytest.approx(50.0 + 0.005 - 0.005)
    assert down.axis_mm[0] == pytest.approx(50.0 + 0.005 + 0.005)
    assert up.straightness_um.shape == (1, 2) and up.angles_urad.shape == (1, 3)
    assert up.straightness_um[0, 0] == pytest.approx(1.0)


def test_repeatability_draw_once_per_move_and_seeded():
    err = StageErrorModel(repeatability_um=2.0)
    def run(seed):
        st = make(errors=err, seed=seed)
        out = []
        for x in (10.0, 20.0, 30.0, 40.0):
            st.move_to(x, 3000.0)
            st.wait_idle()
            a, b = st.true_pose().axis_mm[0], st.true_pose().axis_mm[0]
            assert a == b  # no new draw without a move
            out.append(a - x)
        return np.array(out) * 1e3
    r0, r0b, r1 = run(0), run(0), run(1)
    assert np.array_equal(r0, r0b) and not np.array_equal(r0, r1)
    assert np.all(np.abs(r0) < 5 * 2.0) and np.ptp(r0) > 0


def test_soft_limit_move_alarms_jog_errors():
    """The machine model's reasons are neutral (GRBL's error:15, ALARM:2, error:9 are the emulator's: test_grbl_*)."""
    st = make(travel_mm=(0.0, 100.0))
    with pytest.raises(StageRefused, match="jog to 150.000 mm: the jog's target is outside the travel") as e:
        st.jog(150.0, 1000.0)
    assert e.value.reason is Refusal.BEYOND_TRAVEL and st.status().state == "Idle"
    alarms = []
    st.events.subscribe(lambda ev: ev.kind == "alarm" and alarms.append(ev.reason))
    with pytest.raises(StageAlarm, match="outside its travel 0..100 mm: alarm: a move's target is outside") as a:
        st.move_to(120.0, 1000.0)
    assert a.value.alarm is Alarm.SOFT_LIMIT
    assert st.status().state == "Alarm" and alarms == [Alarm.SOFT_LIMIT] and st.alarm is Alarm.SOFT_LIMIT
    with pytest.raises(StageRefused, match="stage in Alarm: commands are locked out") as e:
        st.move_to(10.0, 1000.0)
    assert e.value.reason is Refusal.LOCKED
    st.unlock()
    st.move_to(10.0, 1000.0)
    assert st.wait_idle().work_mm[0] == pytest.approx(10.0)


def test_homing_lock_and_homing():
    st = make(homing_required=True, travel_mm=(-5.0, 100.0), start_mm=50.0)
    assert st.status().state == "Alarm"
    with pytest.raises(HardwareError, match="home"):
        st.wait_idle()
    st.start_home()
    assert st.status().state == "Home"
    with pytest.raises(StageRefused, match="home in Home: the stage must be idle") as e:
        st.start_home()  # homing while homing is not idle
    assert e.value.reason is Refusal.NOT_IDLE
    st.wait_idle()
    st.move_to(30.0, 3000.0)
    st.wait_idle()
    st.home()
    s = st.status()
    assert s.state == "Idle" and st.homed
    assert s.work_mm[0] == pytest.approx(st.home_position_mm()) == pytest.approx(-4.0)


def test_feed_hold_resume_and_jog_cancel():
    clock = SimClock()
    st = make(clock=clock)
    st.move_to(100.0, 3000.0)
    clock.advance(1.0)
    st.feed_hold()
    assert (st.status().state, st.status().substate) == ("Hold", 1)
    clock.advance(0.3)  # 50 mm/s stops in 0.25 s
    s = st.status()
    assert (s.state, s.substate) == ("Hold", 0)
    assert s.work_mm[0] == pytest.approx(43.75 + 50 * 0.25 / 2)
    st.resume()
    assert st.wait_idle().work_mm[0] == pytest.approx(100.0)
    st.jog(200.0, 3000.0)
    clock.advance(1.0)
    assert st.status().state == "Jog"
    st.jog_cancel()
    s = st.wait_idle()
    assert 100.0 < s.work_mm[0] < 160.0


def test_reset_during_motion_is_an_abort_alarm():
    clock = SimClock()
    st = make(clock=clock)
    st.move_to(100.0, 3000.0)
    clock.advance(0.5)
    st.soft_reset()
    assert st.status().state == "Alarm"
    with pytest.raises(StageAlarm, match="stopped at once during motion") as e:
        st.wait_idle()
    assert e.value.alarm is Alarm.ABORT_DURING_CYCLE


def test_wait_idle_times_out_in_hold():
    st = make()
    st.move_to(100.0, 3000.0)
    st.feed_hold()
    with pytest.raises(HardwareError, match="still Hold after 5 s"):
        st.wait_idle(timeout_s=5.0)


def test_vanished_port_raises_until_reconnect():
    clock = SimClock()
    st = make(clock=clock)
    st.move_to(100.0, 3000.0)
    st.disconnect_fault(at_time_s=1.0)
    with pytest.raises(HardwareError, match="port vanished"):
        st.wait_idle()
    assert not st.connected
    with pytest.raises(HardwareError, match="reconnect"):
        st.status()
    st.connect()
    s = st.status()
    assert s.state == "Idle" and s.work_mm[0] == pytest.approx(43.75)
    st.move_to(100.0, 3000.0)
    assert st.wait_idle().work_mm[0] == pytest.approx(100.0)


def test_not_connected_is_clear():
    st = SimulatedStage()
    with pytest.raises(HardwareError, match="connect the stage first"):
        st.move_to(1.0, 100.0)


def test_settings_read_write_rules():
    """Named settings (GRBL's $110, $22, $20 rules are the emulator's: test_grbl_emulator)."""
    st = make()
    rate, homing, soft = NUMBER["max_rate_mm_min.X"], NUMBER["homing"], NUMBER["soft_limits"]
    names = {s.number: s for s in st.read_settings()}
    assert names[rate].value == 3000.0 and names[rate].unit == "mm/min" and names[rate].name == "X maximum rate"
    assert st.setting_label(names[rate]) == "max_rate_mm_min.X"
    st.write_setting(rate, 1200.0)
    st.move_to(100.0, 3000.0)  # capped at the maximum rate
    assert st.status().feed_mm_min <= 1200.0
    st.wait_idle()
    refused = [(99, 1.0, Refusal.UNKNOWN_SETTING), (rate, -1.0, Refusal.NEGATIVE_VALUE)]
    for number, value, reason in refused:
        with pytest.raises(StageRefused) as e:
            st.write_setting(number, value)
        assert e.value.reason is reason
    st.write_setting(homing, 0)
    assert {s.number: s.value for s in st.read_settings()}[soft] == 0.0  # homing off turns soft limits off
    with pytest.raises(StageRefused, match="soft limits need homing") as e:
        st.write_setting(soft, 1)
    assert e.value.reason is Refusal.SOFT_LIMITS_NEED_HOMING
    with pytest.raises(StageRefused, match="homing is not enabled") as e:
        st.home()
    assert e.value.reason is Refusal.HOMING_DISABLED


def test_full_planner_waits_in_clock_time_and_never_spins_in_a_hold():
    clock = SimClock()
    st = make(clock=clock)
    for i in range(16):  # one more than the 15 blocks: the 16th waits for the first to finish
        st.move_to(10.0 + i, 3000.0)
    assert clock.now() > 0.0 and st.planner_free() == 0
    st.feed_hold()
    clock.advance(1.0)
    with pytest.raises(HardwareError, match="planner full while held"):
        st.move_to(50.0, 3000.0)
    st.resume()
    assert st.wait_idle().work_mm[0] == pytest.approx(25.0)


def test_six_work_systems_keep_their_own_offsets_and_limits_stay_in_machine_space():
    st = make(travel_mm=(0.0, 100.0), start_mm=40.0)
    assert st.work_offsets() == {name: (0.0, 0.0, 0.0) for name in st.work_systems}  # work = machine at start
    st.set_work_zero("X", 10.0)  # G54: here reads 10
    assert st.work_offsets()["G54"] == (30.0, 0.0, 0.0)
    st.select_work_system("G55")
    assert st.work_system() == "G55" and st.status().work_mm[0] == pytest.approx(40.0)
    st.set_work_zero("X")
    st.move_to(-20.0, 3000.0)
    assert st.wait_idle().machine_mm[0] == pytest.approx(20.0)
    with pytest.raises(StageRefused) as e:
        st.jog(-30.0, 1000.0)  # machine -10: beyond the low end
    assert e.value.reason is Refusal.BEYOND_TRAVEL
    with pytest.raises(StageAlarm, match=r"travel -40\.\.60 mm: alarm") as a:
        st.move_to(70.0, 1000.0)  # the travel named in work coordinates
    assert a.value.alarm is Alarm.SOFT_LIMIT
    st.unlock()
    st.select_work_system("G54")
    assert st.status().work_mm[0] == pytest.approx(-10.0)


def test_dead_band_moves_shorter_than_it_leave_the_carriage_there():
    """Stick-slip (ASME B5.64 incremental-step test): 2 um commands into a 3 um dead band move every other time."""
    clock = SimClock()
    stage = SimulatedStage(errors=StageErrorModel(dead_band_um=3.0), clock=clock)
    stage.connect()
    true_um = []
    for target in (0.0, 0.002, 0.004, 0.006, 0.008):
        stage.move_to(target, 600.0)
        stage.wait_idle()
        assert stage.position_mm() == pytest.approx(target)  # the controller reports its steps, not the carriage
        true_um.append(1e3 * float(stage.true_pose().axis_mm[0]))
    assert np.allclose(true_um, [0.0, 0.0, 4.0, 4.0, 8.0], atol=1e-9)
