"""The simulated stage as an XY gantry: per-axis truth, backlash sides and soft limits."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.truth.stage_errors import PlanarErrorModel, StageErrorModel
from lps_gui.hardware.refusals import StageAlarm
from lps_gui.hardware.sim_stage import SimulatedStage


def gantry(**kw) -> SimulatedStage:
    errors = PlanarErrorModel(StageErrorModel(scale_ppm=100.0, backlash_um=10.0),
                              StageErrorModel(scale_ppm=-50.0, backlash_um=6.0), squareness_urad=200.0)
    st = SimulatedStage(planar_errors=errors, travel_mm=(-5.0, 300.0), axis_travel_mm={"Y": (-5.0, 100.0)}, **kw)
    st.connect()
    return st


def move(st: SimulatedStage, x: float, y: float) -> None:
    st.move_to(x, 1000.0, "X")
    st.move_to(y, 1000.0, "Y")
    st.wait_idle()


def test_true_planar_pose_follows_the_error_model_and_each_axis_backlash_side():
    st = gantry()
    move(st, 100.0, 50.0)
    pose = st.true_planar_pose()
    errors = st.planar_errors
    expected = errors.true_pose(np.array([[100.0, 50.0]]), np.array([[1.0, 1.0]])).plane_mm
    assert np.allclose(pose.plane_mm, expected, atol=1e-9)
    move(st, 120.0, 50.0)
    move(st, 100.0, 50.0)  # X now approached from above: X overshoots by the backlash, Y unchanged
    after = st.true_planar_pose()
    assert after.plane_mm[0, 0] - pose.plane_mm[0, 0] == pytest.approx(10e-3, abs=1e-9)
    assert after.plane_mm[0, 1] == pytest.approx(pose.plane_mm[0, 1], abs=1e-9)


def test_soft_limits_per_axis():
    st = gantry()
    with pytest.raises(StageAlarm, match="Y to 150.000 mm is outside its travel -5..100"):
        st.move_to(150.0, 1000.0, "Y")


def test_a_line_stage_has_no_planar_truth():
    st = SimulatedStage()
    with pytest.raises(ValueError, match="no planar error model"):
        st.true_planar_pose()


def test_describe_names_both_axes():
    d = gantry().describe()
    assert d["axes"] == ["X", "Y"] and d["planar_errors"]["squareness_urad"] == 200.0
