"""The simulated rig: the camera sees where the stage really is; the rig survives a trip through session.json."""
from __future__ import annotations

import numpy as np

from lps_gui.camera import open_camera
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.sim.rig import make_simulated_rig, rig_truth, spec_for_plan, spec_from_truth, stage_travel_mm
from tests.capture.helpers import tiny_spec

PLAN = Plan(start_mm=10.0, stop_mm=30.0, step_mm=5.0, overshoot_mm=2.0)


def test_camera_renders_at_the_stage_true_pose():
    spec = tiny_spec(PLAN)
    stage, camera = make_simulated_rig(spec)
    stage.connect()
    camera.open()
    stage.move_to(20.0, 600.0)
    stage.wait_idle()
    frame = camera.grab()
    truth = stage.true_pose().axis_mm[0]
    assert frame.meta["true_axis_mm"] == truth
    expected_um = spec.rig.errors.positioning_error_um(np.array([20.0]), np.array([1.0]))[0]
    assert abs((truth - 20.0) * 1e3 - expected_um) < 5 * spec.rig.errors.repeatability_um
    assert frame.time == stage.clock.now()  # one clock for both


def test_seed_capture_makes_noise_a_function_of_the_index():
    spec = tiny_spec(PLAN)
    stage, camera = make_simulated_rig(spec)
    stage.connect()
    camera.open()
    images = []
    for _ in range(2):
        camera.seed_capture(3)
        images.append(camera.grab().image)
    camera.seed_capture(4)
    other = camera.grab().image
    assert np.array_equal(images[0], images[1]) and not np.array_equal(images[0], other)


def test_rig_round_trips_through_session_truth():
    spec = spec_for_plan("small", PLAN, seed=5)
    stage, camera = make_simulated_rig(spec)
    again = spec_from_truth(rig_truth(spec, camera), PLAN)
    for name in ("R_cam_board", "C0_board", "u_board"):
        np.testing.assert_array_equal(getattr(again.rig, name), getattr(spec.rig, name))
    assert again.rig.errors == spec.rig.errors and again.rig.board == spec.rig.board and again.seed == 5
    assert again.rig.intrinsics.image_size == spec.rig.intrinsics.image_size


def test_spec_for_plan_centres_the_board_over_the_travel():
    spec = spec_for_plan("small", Plan(start_mm=200.0, stop_mm=260.0, step_mm=10.0))
    mid_C = spec.rig.C0_board + 230.0 * spec.rig.u_board
    ref = spec_for_plan("small")
    t = ref.plan.targets()
    ref_mid_C = ref.rig.C0_board + 0.5 * (t[0] + t[-1]) * ref.rig.u_board
    np.testing.assert_allclose(mid_C, ref_mid_C, atol=1e-9)
    assert stage_travel_mm(PLAN) == (-5.0, 500.0)
    lo, hi = stage_travel_mm(Plan(start_mm=-20.0, stop_mm=600.0, step_mm=20.0, overshoot_mm=1.0))
    assert lo <= -21.0 and hi >= 601.0


def test_open_camera_sim_needs_the_rig():
    spec = tiny_spec(PLAN)
    stage, _ = make_simulated_rig(spec)
    stage.connect()
    cam = open_camera("sim", rig=spec.rig, pose_source=stage.true_pose, clock=stage.clock)
    assert cam.is_open and cam.grab().image.shape == (240, 320)
    assert StageErrorModel.from_dict(stage.describe()["errors"]) == spec.rig.errors
