"""The truth a constant-orientation model can see: displacement at the board plane."""
from dataclasses import replace

import numpy as np

from lps_gui.core.truth.simulate import board_plane_positions, paper_rig_spec
from lps_gui.core.truth.stage_errors import TruePose


def pose(axis, angles=None):
    K = len(axis)
    return TruePose(np.asarray(axis, float), np.zeros((K, 2)), np.zeros((K, 3)) if angles is None else np.asarray(angles, float))


def test_without_angular_errors_it_is_the_axis_position():
    rig = paper_rig_spec().rig
    axis = np.array([0.0, 1.0, 2.5, 40.0])
    assert np.allclose(board_plane_positions(rig, pose(axis)), axis, atol=1e-9)


def test_a_pitch_about_v1_adds_the_abbe_term_distance_times_angle():
    rig = replace(paper_rig_spec().rig)
    axis = np.array([0.0, 10.0, 20.0])
    theta_urad = 50.0
    angles = np.array([[0.0, 0.0, 0.0], [0.0, theta_urad, 0.0], [0.0, 0.0, 0.0]])  # pitch about v1 at the middle stop
    plane = board_plane_positions(rig, pose(axis, angles))
    # the board centre's line of sight moves by the lever (camera -> board centre along v2) times the angle
    frame = rig.frame()
    C = rig.C0_board + axis[1] * frame[:, 0]
    lever_mm = (rig.board.object_points().mean(axis=0) - C) @ frame[:, 2]
    assert 590.0 < lever_mm < 610.0  # the paper rig's 600 mm
    np.testing.assert_allclose(1e3 * (plane[1] - axis[1]), lever_mm * theta_urad * 1e-3, rtol=1e-3)
    assert np.allclose(plane[[0, 2]], axis[[0, 2]], atol=1e-9)


def test_a_roll_tilts_the_board_plane_path_and_the_positions_follow_it():
    """A roll growing along the travel moves the board centre's line of sight sideways by (lever x roll): the
    path at the board plane is a line tilted off the axis by k = lever x roll rate, and the positions are the
    distances along it (sqrt(1 + k^2) x the axis'), not their projection on the axis direction."""
    rig = paper_rig_spec().rig
    axis = np.linspace(0.0, 100.0, 11)
    rate_urad_per_mm = 20.0
    angles = np.stack([rate_urad_per_mm * axis, np.zeros_like(axis), np.zeros_like(axis)], axis=1)
    plane = board_plane_positions(rig, pose(axis, angles))
    frame = rig.frame()
    lever_mm = (rig.board.object_points().mean(axis=0) - rig.C0_board) @ frame[:, 2]
    k = lever_mm * rate_urad_per_mm * 1e-6
    np.testing.assert_allclose(plane - plane[0], (axis - axis[0]) * np.sqrt(1.0 + k * k), rtol=0, atol=2e-4)
    assert np.max(np.abs(plane - axis)) > 5e-3  # the tilt's lengthening (um) is there: the test has teeth
