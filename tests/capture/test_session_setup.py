"""lps_gui.capture.setup: the operator's session set-up, checked once for both faces."""
from __future__ import annotations

import pytest

from lps_gui.capture.setup import SessionSetup, apply_setup, asme_plan_fields
from lps_gui.core.planning.presets import min_step_plan_fields
from lps_gui.errors import InputError


class FakeSession:
    def __init__(self, meta):
        self.meta, self.saved = meta, 0

    def save_meta(self):
        self.saved += 1


def test_only_what_was_given_goes_into_session_json():
    assert SessionSetup().meta() == {}
    setup = SessionSetup(spec={"accuracy_um": 10.0, "repeatability_um": None}, environment={"board_temperature_c": None},
                         env_notes="  ", identification={"operator": "  A. Meier ", "lab": ""}, test="settling")
    assert setup.meta() == {"stage_spec": {"accuracy_um": 10.0}, "asme_test": {"test": "settling", "band_um": 5.0},
                            "identification": {"operator": "A. Meier"}}
    assert SessionSetup(spec="paper").meta() == SessionSetup(
        spec={"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0}).meta()


@pytest.mark.parametrize("setup,match", [
    (SessionSetup(spec={"accuracy_um": -1.0}, where="form"), "form: specification accuracy_um"),
    (SessionSetup(spec="accuracy=x"), "--spec accuracy"),
    (SessionSetup(environment={"board_temperature_c": 400.0}, where="form"), "form: board_temperature_c"),
    (SessionSetup(environment={"square_mm_uncertainty_um": -0.1}), "cannot be negative"),
    (SessionSetup(test="vibration"), "--test vibration"),
])
def test_a_bad_entry_is_one_line_naming_it(setup, match):
    with pytest.raises(InputError, match=match):
        setup.meta()


def test_a_resumed_session_keeps_what_nothing_new_replaces():
    session = FakeSession({"environment": {"board_temperature_c": 21.0}, "stage_spec": {"accuracy_um": 5.0}})
    apply_setup(session, SessionSetup(spec={"repeatability_um": 2.0}, environment={"stage_temperature_c": 22.0}).meta())
    assert session.meta == {"environment": {"board_temperature_c": 21.0, "stage_temperature_c": 22.0},
                            "stage_spec": {"repeatability_um": 2.0}} and session.saved == 1
    apply_setup(session, {})
    assert session.saved == 1


def test_the_asme_plans_are_the_presets():
    assert asme_plan_fields("min-step", 0, 8, step_um=1.0) == min_step_plan_fields(0.0, 8.0, step_um=1.0)
    with pytest.raises(InputError, match="--test drift"):
        asme_plan_fields("drift", 0, 8)


def test_both_faces_record_the_devices_alike():
    """session.json ``stage`` carries the driver's declared capabilities (SPEC 16) and, when the face knows it,
    the source the device was opened from; the GUI once recorded the description only."""
    from lps_gui.camera.sim_camera import SimulatedCamera
    from lps_gui.capture.setup import device_records
    from lps_gui.core.clock import SimClock
    from lps_gui.core.truth.simulate import small_spec
    from lps_gui.hardware.sim_stage import SimulatedStage

    spec, clock = small_spec(), SimClock()
    stage = SimulatedStage(errors=spec.rig.errors, clock=clock)
    camera = SimulatedCamera(spec.rig, stage.true_pose, clock=clock)
    stage_record, camera_record = device_records(stage, camera, "sim", "sim", axes=["X"])
    assert stage_record["capabilities"] and stage_record["spec"] == "sim" and stage_record["axes"] == ["X"]
    assert camera_record == {**camera.properties(), "spec": "sim"}
    bare = device_records(stage, camera)
    assert "spec" not in bare[0] and "spec" not in bare[1] and bare[0]["capabilities"] == stage_record["capabilities"]
