"""ASME B5.64 tests through the one estimation path, against the point simulator's truth (issue 25 must-shows).

The paper camera 450 mm from its board (preset paper-closeup): 2 um steps, 8 frames per stop, resolve
(each step's sigma under 1 um) on a good stage and show a 3 um dead band as a stage that sticks; the
settling time of a ringing stage within 20 % of its true settling time.
"""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.presets import asme_test_record, min_step_plan_fields, settling_plan_fields
from lps_gui.core.truth.simulate import preset
from lps_gui.core.truth.stage_errors import Vibration
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


def _min_step_session(folder, dead_band_um: float, spec_limits: dict | None, seed: int = 0):
    spec = preset("paper-closeup", seed=seed)
    spec = replace(spec, plan=Plan(**min_step_plan_fields(0.0, 200.0)),
                   rig=replace(spec.rig, errors=replace(spec.rig.errors, dead_band_um=dead_band_um)))
    session = simulate_point_session(spec, folder)
    session.meta["asme_test"] = asme_test_record("min-step")
    if spec_limits:
        session.meta["stage_spec"] = spec_limits
    session.save_meta()
    return session


def _true_steps_um(results: dict, session) -> np.ndarray:
    """The simulator's true step between the averaged stops of each measured step (each target is visited
    once per direction: a stop is (target, direction))."""
    axis = np.asarray(session.truth["axis_mm"])
    by_stop: dict[tuple[float, str], list[float]] = {}
    for r in session.records():
        by_stop.setdefault((round(r.target_mm, 9), r.direction), []).append(axis[r.index])
    mean = {k: float(np.mean(v)) for k, v in by_stop.items()}
    return np.array([1e3 * (mean[(round(s["to_mm"], 9), s["direction"])] - mean[(round(s["from_mm"], 9), s["direction"])])
                     for s in results["asme_b5_64"]["incremental_step"]["steps"]])


def test_two_micrometre_steps_with_eight_frames_are_resolved(tmp_path):
    session = _min_step_session(tmp_path / "s", 0.0, {"accuracy_um": 20.0, "min_incremental_motion_um": 2.0})
    results = estimate_session(session.folder)
    step = results["asme_b5_64"]["incremental_step"]
    assert step["frames_per_stop"] == 8 and step["n_steps"] == 60
    assert step["max_step_sigma_um"] < 1.0  # must show: each step's sigma under 1 um
    assert step["n_resolved"] == 60 and not step["sticks"] and step["minimum_incremental_motion_um"] == 2.0
    achieved = np.array([s["achieved_um"] for s in step["steps"]])
    sigma = np.array([s["sigma_um"] for s in step["steps"]])
    z2 = np.mean(((achieved - _true_steps_um(results, session)) / sigma) ** 2)  # against truth, not itself
    assert 0.4 < z2 < 2.0
    rows = {r["figure"]: r for r in results["asme_b5_64"]["test_uncertainty_ratio"]}
    assert rows["Minimum incremental motion"]["tur"] == pytest.approx(2.0 / (2.0 * step["max_step_sigma_um"]))
    assert rows["Positional accuracy"]["tolerance"] == 20.0 and "Repeatability" not in rows  # no tolerance: no TUR
    assert {r["symbol"] for r in results["asme_b5_64"]["figures"]} >= {"E", "B"}


def test_a_three_micrometre_dead_band_is_a_stage_that_sticks(tmp_path):
    session = _min_step_session(tmp_path / "s", 3.0, None)
    results = estimate_session(session.folder)
    step = results["asme_b5_64"]["incremental_step"]
    assert step["sticks"] and step["minimum_incremental_motion_um"] is None
    assert step["n_stuck"] >= 20 and step["truth"] == {"dead_band_um": 3.0}
    assert results["asme_b5_64"]["test_uncertainty_ratio"] == []  # no stage_spec: no ratio invented


def test_settling_time_within_20_percent_of_the_truth(tmp_path):
    spec = preset("paper-closeup")
    ring = Vibration(50.0, 8.0, 0.25)
    spec = replace(spec, plan=Plan(**settling_plan_fields(0.0, 200.0, stops=2, frames=80)), vibration=ring,
                   frame_interval_s=0.01)
    session = simulate_point_session(spec, tmp_path / "s")
    session.meta["asme_test"] = asme_test_record("settling", band_um=5.0)
    session.meta["stage_spec"] = {"settling_time_s": 1.0}
    session.save_meta()
    results = estimate_session(session.folder)
    settle = results["asme_b5_64"]["settling"]
    truth = ring.settling_time_s(5.0)
    assert settle["truth"]["settling_time_s"] == pytest.approx(truth)
    assert settle["n_stops"] == 4 and len(settle["stops"][0]["since_move_s"]) == 80
    assert abs(settle["settling_time_s"] / truth - 1.0) < 0.2  # must show
    for stop in settle["stops"]:
        assert abs(stop["settling_time_s"] / truth - 1.0) < 0.2
    assert results["parameters"]["n_outliers"] == 0  # ringing frames are not outliers in a settling test
    row = results["asme_b5_64"]["test_uncertainty_ratio"][0]
    assert row["figure"] == "Settling time" and row["tur"] == pytest.approx(1.0 / settle["settling_time_U_s"])
    assert results["truth_comparison"]["self_check"]["passed"]  # the settling time is checked and holds

    # the estimate's own self-check scores the settling time: a stage that truly rang twice as long contradicts it
    meta = json.loads((session.folder / "session.json").read_text())
    meta["truth"]["vibration"]["decay_s"] = 0.5
    (session.folder / "session.json").write_text(json.dumps(meta))
    problems = estimate_session(session.folder)["truth_comparison"]["self_check"]["problems"]
    assert [p for p in problems if p.startswith("settling time ")], problems


def test_a_min_step_session_has_no_periodic_figure_and_steps_without_the_jumps(tmp_path):
    """Issue 35: the min-step test printed "Periodic error amplitude 240 +- 0.18 um, period 0.680 mm" and
    "Step std 24391 um" (the jumps between its three places). Its clusters define no period; its steps are 2 um."""
    from lps_gui.io.results.document import summary_csv_rows

    session = _min_step_session(tmp_path / "s", 0.0, None)
    results = estimate_session(session.folder)
    single = results["figures"]["single_run"]
    assert single["periodic_amplitude_um"] is None and single["periodic_period_mm"] is None
    assert results["uncertainty"]["figures_k2"].get("periodic_amplitude_um") is None
    true_um = np.abs(_true_steps_um(results, session))  # single-run steps go up the targets in both directions
    assert single["mean_step_mm"] == pytest.approx(1e-3 * true_um.mean(), abs=0.3e-3)
    assert single["step_std_um"] < 3.0 * max(float(np.std(true_um, ddof=1)), 0.5)
    rows = {r[0]: r[1] for r in summary_csv_rows(results)}
    assert rows["periodic_amplitude"] is None and rows["step_std"] == pytest.approx(single["step_std_um"])
