"""Straightness at the board plane through the whole pipeline, and the paper's three spec rows."""
from __future__ import annotations

import numpy as np

from lps_gui.core.metrology.iso230 import check_specification
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec, paper_stage_errors
from lps_gui.io.results.document import POSITION_COLUMNS
from lps_gui.pipeline.demos.run import PAPER_SPEC
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pages.summary import extremes_rows, spec_checks
from lps_gui.sim.points import simulate_point_session
from lps_gui.sim.truth_figures import line_figure_checks


def _session(tmp_path, runs: int, directions: str = "both"):
    plan = Plan(start_mm=0.0, stop_mm=400.0, step_mm=20.0, directions=directions, runs=runs)
    spec = paper_rig_spec(seed=11, errors=paper_stage_errors(), plan=plan)
    simulate_point_session(spec, tmp_path / "s")
    return estimate_session(tmp_path / "s")


def test_five_bidirectional_runs_give_all_three_spec_rows_a_verdict(tmp_path):
    results = _session(tmp_path, runs=5)
    rows = check_specification(results["figures"], PAPER_SPEC)
    assert [r["name"] for r in rows] == ["Positional accuracy", "Repeatability", "Straight-line accuracy"]
    assert all(r["passed"] is not None for r in rows), rows
    assert not any(r["indicative"] for r in rows)
    st = results["figures"]["straightness"]
    assert st["v1"]["resolved"] and st["v1"]["noise_span_um"] < PAPER_SPEC["straightness_um"]
    assert st["v2"]["noise_span_um"] < PAPER_SPEC["straightness_um"]
    # U of the span holds the constant-orientation model's overstatement of a carriage rotation (u_model_um)
    u_model = st["v1"]["u_model_um"]
    assert u_model > 0 and np.isclose(results["uncertainty"]["figures_k2"]["straightness_span_1"],
                                      2.0 * np.hypot(st["v1"]["u_span_um"], u_model))
    [check] = [c for c in line_figure_checks(results) if c["figure"] == "straightness v1"]
    assert abs(check["z"]) <= 2.0, check  # against the simulator's truth
    tc = results["truth_comparison"]
    # against the simulator's board-plane truth (first-order geometry, no solver)
    assert tc["straightness_rms_error_um_1"] < 5.0
    for key in ("straightness_z_mean_square_1", "straightness_z_mean_square_2", "image_rotation_z_mean_square"):
        assert 0.4 < tc[key] < 2.5, (key, tc[key])
    assert {"straightness_um_1", "straightness_um_2"} <= set(POSITION_COLUMNS)
    row = results["positions"][3]
    for key in ("straightness_sigma_um_1", "straightness_sigma_um_2", "image_rotation_urad", "image_rotation_sigma_urad",
                "pose_straightness_um_1"):
        assert row[key] is not None and np.isfinite(row[key])


def test_fewer_runs_are_indicative_and_unresolved_figures_are_not_findings(tmp_path):
    results = _session(tmp_path, runs=1, directions="+")
    checks = spec_checks(results, PAPER_SPEC)
    assert all(c.indicative == (c.name in ("Positional accuracy", "Repeatability")) for c in checks)
    assert all("FAIL" not in c.verdict() for c in checks)
    rows = {r.name: r for r in extremes_rows(results)}
    # one run: v2 per-view sigma ~13 um over 21 targets cannot resolve the paper rig's few-um v2 straightness
    assert rows["Max straightness v2 (peak-to-valley)"].text().startswith("not resolved (noise p-v")
    assert not rows["Max straightness v1 (peak-to-valley)"].unresolved
    for name in ("roll", "pitch"):
        assert rows[f"Max |{name}|"].text().startswith("not resolved")
