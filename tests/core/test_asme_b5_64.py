"""ASME B5.64 figures (core/metrology/asme_b5_64) against their definitions and synthetic truth; the stage's dead band
and ringing (core/truth/stage_errors); the test plan presets (core/planning/presets)."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.metrology.asme_b5_64 import incremental_step_figures, named_figures, settling_figures, tur
from lps_gui.core.planning.presets import asme_test_record, min_step_plan_fields, parse_spec, settling_plan_fields
from lps_gui.core.truth.stage_errors import StageErrorModel, Vibration
from lps_gui.errors import InputError


def test_dead_band_keeps_the_carriage_until_the_command_is_a_dead_band_away():
    reached, moved = StageErrorModel(dead_band_um=3.0).reached_mm(1e-3 * np.array([0, 2, 4, 6, 8, 6, 2]))
    assert np.allclose(1e3 * reached, [0, 0, 4, 4, 8, 8, 2])
    assert moved.tolist() == [True, False, True, False, True, False, True]
    reached, moved = StageErrorModel().reached_mm(1e-3 * np.array([0, 2, 4]))
    assert np.allclose(1e3 * reached, [0, 2, 4]) and moved.all()
    assert "dead_band_um" not in StageErrorModel().to_dict()  # sessions without one are recorded as before
    assert StageErrorModel.from_dict(StageErrorModel(dead_band_um=3.0).to_dict()).dead_band_um == 3.0


@pytest.mark.parametrize("band_um", [2.0, 5.0, 17.0, 60.0])
def test_settling_time_is_the_last_time_outside_the_band(band_um):
    ring = Vibration(50.0, 8.0, 0.25)
    t = np.arange(0.0, 2.0, 1e-5)
    outside = np.flatnonzero(np.abs(ring.offset_um(t)) > band_um)
    brute = t[outside[-1]] if outside.size else 0.0
    assert ring.settling_time_s(band_um) == pytest.approx(brute, abs=2e-5)


def test_settling_fit_recovers_the_settling_time_from_noisy_frames():
    ring = Vibration(50.0, 8.0, 0.25)
    t = 0.01 * np.arange(1, 101)
    rng = np.random.default_rng(3)
    fig = settling_figures(t, 7.0 + ring.offset_um(t) + rng.normal(0.0, 1.5, t.size), 5.0)
    truth = ring.settling_time_s(5.0)
    assert abs(fig["settling_time_s"] - truth) < 0.05 * truth
    assert 0 < fig["settling_time_U_s"] < 0.1
    assert fig["rest_um"] == pytest.approx(7.0, abs=0.5) and fig["frequency_hz"] == pytest.approx(8.0, abs=0.1)
    assert fig["settling_time_frames_s"] >= fig["settling_time_s"] - 0.02  # noise only delays the frames' crossing


def _steps(achieved_um, sigma_um=0.7, d=2.0):
    n = len(achieved_um)
    c = np.where(np.arange(n) < n // 2, d, -d)
    return incremental_step_figures(c, c / d * np.asarray(achieved_um), np.full(n, sigma_um))


def test_incremental_steps_resolved_achieved_and_stuck():
    rng = np.random.default_rng(0)
    good = _steps(2.0 + rng.normal(0.0, 0.7, 60))
    assert good["n_resolved"] == 60 and not good["sticks"] and good["minimum_incremental_motion_um"] == 2.0
    stuck = _steps(np.tile([0.0, 4.0], 30) + rng.normal(0.0, 0.7, 60))
    assert stuck["sticks"] and stuck["minimum_incremental_motion_um"] is None
    assert 25 <= stuck["n_stuck"] <= 35 and stuck["sizes"][0]["n_stuck_by_noise"] < 6
    blurred = _steps(2.0 + rng.normal(0.0, 3.0, 60), sigma_um=3.0)
    assert blurred["n_resolved"] == 0 and blurred["minimum_incremental_motion_um"] is None and not blurred["sticks"]
    assert [s["commanded_um"] for s in good["steps"][:1] + good["steps"][-1:]] == [2.0, -2.0]


def test_tur_needs_a_tolerance_and_names_go_both_ways():
    assert tur(None, 2.0) is None and tur(20.0, None) is None
    assert tur(20.0, 5.0) == 4.0
    rows = named_figures({"A_um": 12.0, "R_um": 3.0, "E_um": None}, {"A_um": 4.0})
    assert [(r["symbol"], r["asme_b5_64"], r["U_um"]) for r in rows] == [
        ("A", "bidirectional positioning accuracy", 4.0), ("R", "bidirectional repeatability", None)]
    assert rows[0]["iso230_2"].startswith("accuracy of positioning A")


def test_test_plan_presets():
    f = min_step_plan_fields(0.0, 100.0, step_um=2.0, steps=5, locations=3, frames=8)
    t = np.asarray(f["targets_mm"])
    assert t.size == 18 and f["frames_per_stop"] == 8 and f["directions"] == "both"
    assert np.allclose(np.diff(t[:6]), 0.002) and t[0] == 0.0 and t[-1] == pytest.approx(100.0)
    with pytest.raises(InputError, match="do not fit"):
        min_step_plan_fields(0.0, 0.01, step_um=2.0, steps=10)
    s = settling_plan_fields(0.0, 10.0, stops=3, frames=50)
    assert s["settle_s"] == 0.0 and s["frames_per_stop"] == 50 and s["targets_mm"] == (0.0, 5.0, 10.0)
    assert asme_test_record("settling") == {"test": "settling", "band_um": 5.0}
    with pytest.raises(InputError, match="--test"):
        asme_test_record("vibration")
    assert parse_spec("paper,min_step=2,settling=0.5") == {"accuracy_um": 20.0, "repeatability_um": 5.0,
                                                           "straightness_um": 38.0, "min_incremental_motion_um": 2.0,
                                                           "settling_time_s": 0.5}


def test_a_step_is_never_both_achieved_and_stuck():
    """Issue 37: a 2 um step that moved -0.44 um (sigma 0.75) counted as achieved and as stuck."""
    fig = incremental_step_figures(np.array([2.0, 2.0, 2.0]), np.array([-0.44, 2.1, -1.5]), np.array([0.75, 0.75, 0.3]))
    steps = fig["steps"]
    assert not any(s["achieved"] and s["stuck"] for s in steps)
    assert steps[0]["achieved"] and not steps[0]["stuck"] and steps[0]["below_half"]  # a miss needs evidence
    assert steps[2]["stuck"] and not steps[2]["achieved"]
    assert fig["n_stuck"] == 2  # the sticking test counts every step below half its command
