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
    distance_mm = 600.0
    shift_um = 1e3 * abs(plane[1] - axis[1])
    # a rotation moves off-axis corners by f (1 + x'^2) theta, a translation by f d / Z: the best-fitting
    # translation is the on-axis Abbe term lengthened by the board's angular extent (~10-15 % here)
    abbe_um = distance_mm * theta_urad * 1e-3
    assert abbe_um <= shift_um < 1.25 * abbe_um
    assert np.allclose(plane[[0, 2]], axis[[0, 2]], atol=1e-9)
