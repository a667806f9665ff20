"""What the engine needs from a device is declared on Stage and Camera; the simulated rig's draws go through
one explicit hook (SimulatorHook), not through methods the engine probes for."""
from __future__ import annotations

import pytest

from lps_gui.camera.opencv_camera import OpenCVCamera
from lps_gui.camera.sim_camera import SimulatedCamera
from lps_gui.capture.engine import CaptureEngine
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.stage import Stage
from lps_gui.io.session import Session
from lps_gui.sim.session import SimulatedRigHook
from tests.capture.helpers import image_bytes, records_without_time, start_capture, tiny_spec

PLAN = Plan(start_mm=0.0, stop_mm=6.0, step_mm=2.0, directions="both", settle_s=0.0)


def test_a_real_driver_declares_what_it_does_not_know():
    assert GrblStage.travel_mm is None and GrblStage.axis_travel_mm is None and GrblStage.clock is None
    assert GrblStage.simulated is None and Stage.true_pose(GrblStage.__new__(GrblStage)) is None
    assert OpenCVCamera("folder/clip.avi").property_device() is None  # files and streams have no controls
    assert OpenCVCamera(0).property_device() is None  # closed


def test_the_simulated_stage_declares_its_travel_and_clock_and_the_engine_checks_them(tmp_path):
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=PLAN)
    assert engine.clock is stage.clock
    assert isinstance(camera, SimulatedCamera) and camera.pose_source == stage.true_pose
    assert isinstance(engine.simulator, SimulatedRigHook) and engine.simulator.stage is stage
    stage.travel_mm = (0.0, 100.0)  # the first overshoot (-1 mm) is beyond the low limit
    with pytest.raises(InputError, match="stage travels 0..100 mm"):
        engine.run()


def test_without_the_simulator_hook_nothing_is_seeded_and_with_it_a_rerun_draws_the_same(tmp_path):
    first, *_, engine = start_capture(tmp_path / "a", plan=PLAN)
    assert engine.run().state == "done"
    second, *_, engine = start_capture(tmp_path / "b", plan=PLAN)
    assert engine.run().state == "done"
    assert records_without_time(first) == records_without_time(second) and image_bytes(first) == image_bytes(second)

    from lps_gui.sim.session import create_simulated_session

    session, stage, camera = create_simulated_session(tmp_path / "plain", tiny_spec(PLAN))
    stage.connect()
    unseeded = CaptureEngine(stage, camera, Session.open(session.folder))  # no hook: the rig's own streams
    assert unseeded.simulator is None and unseeded.run().state == "done"
    assert image_bytes(session) != image_bytes(first)
