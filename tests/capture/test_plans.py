"""Plan files, switch overrides and the duration estimate."""
from __future__ import annotations

import json

import pytest

from lps_gui.capture.plans import describe_plan, parse_targets, plan_duration_s, plan_with, read_plan
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError
from tests.capture.helpers import PLAN20, start_capture


def test_read_plan_from_plan_file_or_session_json(tmp_path):
    (tmp_path / "plan.json").write_text(json.dumps({"targets_mm": [3, 1, 2], "directions": "both"}))
    plan = read_plan(tmp_path / "plan.json")
    assert list(plan.targets()) == [1.0, 2.0, 3.0] and plan.directions == "both"
    (tmp_path / "session.json").write_text(json.dumps({"format": "lps-session/1", "plan": PLAN20.to_dict()}))
    assert read_plan(tmp_path / "session.json") == PLAN20
    (tmp_path / "bad.json").write_text(json.dumps({"directions": "sideways"}))
    with pytest.raises(InputError, match="bad.json: plan: directions"):
        read_plan(tmp_path / "bad.json")


def test_switches_override_the_plan():
    base = Plan(targets_mm=(0.0, 5.0))
    assert plan_with(base, start_mm=0.0, stop_mm=4.0, step_mm=2.0).targets().tolist() == [0.0, 2.0, 4.0]
    assert plan_with(base, runs=3).targets_mm == (0.0, 5.0)
    assert plan_with(None, targets_mm=parse_targets("0; 1.5,3")).targets().tolist() == [0.0, 1.5, 3.0]
    with pytest.raises(InputError, match="comma-separated"):
        parse_targets("0,x")
    assert describe_plan(PLAN20) == "20 targets 0..38 mm, forward and backward, 2 run(s), 1 frame(s) per stop: 80 frames"


def test_duration_estimate_matches_the_simulated_capture(tmp_path):
    plan = Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, directions="both", settle_s=0.5, feed_mm_min=600.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    summary = engine.run()
    estimate = plan_duration_s(plan, accel_mm_s2=stage.accel_mm_s2(0), grab_s=0.0)
    assert estimate == pytest.approx(summary.elapsed_s, rel=0.02)
