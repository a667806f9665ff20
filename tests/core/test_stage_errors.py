"""core/truth/stage_errors: the one truth of every simulator, term by term."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel


def test_error_profile_polynomial_in_metres_plus_sine():
    p = ErrorProfile(poly=(1.0, 2.0, 3.0), amplitude=0.5, period_mm=10.0, phase_rad=0.25)
    x = np.array([0.0, 250.0, 1000.0])
    xm = x / 1000.0
    assert np.allclose(p(x), 1.0 + 2.0 * xm + 3.0 * xm**2 + 0.5 * np.sin(2 * np.pi * x / 10.0 + 0.25))
    assert np.all(ErrorProfile()(x) == 0.0)


def test_positioning_error_scale_periodic_and_backlash():
    m = StageErrorModel(scale_ppm=50.0, periodic_um=3.0, pitch_mm=5.0, periodic_phase_rad=0.0, backlash_um=8.0)
    x = np.array([0.0, 1.25, 100.0])
    up = m.positioning_error_um(x, +1)
    down = m.positioning_error_um(x, -1)
    expected_up = 50.0 * x * 1e-3 + 3.0 * np.sin(2 * np.pi * x / 5.0) - 4.0
    assert np.allclose(up, expected_up)
    assert np.allclose(up - down, -8.0)  # moving up stops short by half the backlash, down overshoots by half


def test_true_pose_shapes_noise_and_systematic_part():
    m = StageErrorModel(scale_ppm=10.0, repeatability_um=2.0, straightness_um=(ErrorProfile(poly=(0.0, 5.0)), ErrorProfile()),
                        yaw_urad=ErrorProfile(amplitude=7.0, period_mm=40.0))
    x = np.linspace(0.0, 100.0, 2001)
    sys_pose = m.true_pose(x, np.ones_like(x))
    assert sys_pose.straightness_um.shape == (x.size, 2) and sys_pose.angles_urad.shape == (x.size, 3)
    assert np.allclose(sys_pose.axis_mm, x + 1e-3 * m.positioning_error_um(x, 1))
    noisy = m.true_pose(x, np.ones_like(x), np.random.default_rng(0))
    resid_um = 1e3 * (noisy.axis_mm - sys_pose.axis_mm)
    assert abs(np.std(resid_um) - 2.0) < 0.1 and abs(np.mean(resid_um)) < 0.15
    assert np.allclose(sys_pose.angles_urad[:, 2], 7.0 * np.sin(2 * np.pi * x / 40.0))


def test_dict_round_trip_is_exact():
    m = StageErrorModel(scale_ppm=1.5, periodic_um=2.0, pitch_mm=4.0, backlash_um=3.0, repeatability_um=0.5,
                        straightness_um=(ErrorProfile(poly=(1.0, 2.0)), ErrorProfile(amplitude=3.0, period_mm=9.0)),
                        pitch_urad=ErrorProfile(poly=(0.0, 0.0, 4.0)))
    again = StageErrorModel.from_dict(m.to_dict())
    assert again == m
    assert StageErrorModel.from_dict(None) == StageErrorModel()


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_a_scalar_commanded_position_gives_one_pose(direction):
    pose = StageErrorModel(backlash_um=2.0).true_pose(10.0, direction)
    assert pose.axis_mm.shape == (1,) and pose.axis_mm[0] == pytest.approx(10.0 - direction * 1e-3)


def test_angle_noise_is_drawn_per_stop_and_kept_out_of_older_truth_records():
    smooth = StageErrorModel(roll_urad=ErrorProfile(amplitude=80.0, period_mm=600.0))
    noisy = StageErrorModel(roll_urad=ErrorProfile(amplitude=80.0, period_mm=600.0), angle_noise_urad=3.0)
    x = np.linspace(0.0, 600.0, 2000)
    d = np.ones_like(x)
    e = noisy.true_pose(x, d, np.random.default_rng(1)).angles_urad - smooth.true_pose(x, d).angles_urad
    assert np.allclose(e.std(axis=0), 3.0, rtol=0.1) and np.abs(e.mean(axis=0)).max() < 0.3
    assert np.array_equal(noisy.true_pose(x, d).angles_urad, smooth.true_pose(x, d).angles_urad)  # no rng: systematic
    assert "angle_noise_urad" not in smooth.to_dict()
    assert StageErrorModel.from_dict(noisy.to_dict()) == noisy
