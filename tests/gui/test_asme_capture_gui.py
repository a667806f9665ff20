"""The capture panel's ASME B5.64 test presets: the plan of lps capture --test, recorded in session.json."""
from __future__ import annotations

import json

import pytest

from lps_gui.core.planning.presets import asme_test_record, min_step_plan_fields, settling_plan_fields
from tests.gui.test_capture_flow import SMALL_PLAN, capture_window, records

pytestmark = pytest.mark.gui


def test_the_min_step_preset_sets_the_plan_and_goes_into_session_json(qtbot, make_window, tmp_path):
    folder = tmp_path / "min-step"
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, folder)
    assert cap.test_name() is None and cap.asme_test_meta() == {}
    cap.asme_test.setCurrentIndex(cap.asme_test.findData("min-step"))
    fields = min_step_plan_fields(0.0, 8.0)
    plan = cap.plan()
    assert plan.targets_mm == fields["targets_mm"] and plan.frames_per_stop == 8 and plan.directions == "both"
    assert "ASME B5.64 min-step test" in cap.summary.text()
    cap.start_btn.click()
    job = cap.job
    assert job is not None
    qtbot.waitUntil(lambda: len(records(folder)) >= 1, timeout=30000)
    with qtbot.waitSignal(job.finished, timeout=30000):
        cap.abort_btn.click()  # the session is written before the first frame: the test is in it
    assert json.loads((folder / "session.json").read_text())["asme_test"] == asme_test_record("min-step")

    cap.asme_test.setCurrentIndex(cap.asme_test.findData("settling"))
    plan = cap.plan()
    fields = settling_plan_fields(0.0, 8.0)
    assert plan.targets_mm == fields["targets_mm"] and plan.frames_per_stop == 100 and plan.settle_s == 0.0
    cap.stop_mm.setValue(20.0)  # the range changed by hand: the plan is no longer the test's
    assert cap.test_name() is None and cap.plan().targets_mm is None and cap.asme_test_meta() == {}


def test_a_test_that_does_not_fit_the_travel_is_a_one_line_refusal(qtbot, make_window, tmp_path):
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, tmp_path / "s")
    cap.step_mm.setValue(0.01)
    cap.stop_mm.setValue(0.05)  # 3 places of 10 steps of 2 um do not fit 0..0.05 mm
    cap.asme_test.setCurrentIndex(cap.asme_test.findData("min-step"))
    assert cap.test_name() is None and "do not fit" in cap.summary.text()
