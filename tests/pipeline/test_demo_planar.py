"""`lps demo --planar --quick`: the planar pipeline end to end on the simulated gantry, its printout
taken from results.json (figures and truth_comparison), and the report written."""
from __future__ import annotations

import json

from lps_gui.pipeline.demos.run import demo_spec
from lps_gui.pipeline.demos.summary import planar_summary_lines


def test_demo_plans_have_lines_along_both_axes():
    for quick in (True, False):
        plan = demo_spec(quick, planar=True).plan
        t = plan.targets()
        assert plan.directions == "both"
        assert len(set(t[:, 0])) >= 3 and len(set(t[:, 1])) >= 3  # ISO 230-2 lines and straightness per axis
    assert demo_spec(True, planar=True).rig.intrinsics.image_size == (640, 480)
    assert demo_spec(False, planar=True).plan.n_frames() <= 100  # well under a minute of rendering


def test_quick_planar_demo_runs_end_to_end(quick_planar_demo):
    session = quick_planar_demo / "session"  # made once per test run (tests/conftest.py)
    results = json.loads((session / "results.json").read_text())
    assert results["axes"] == ["X", "Y"] and (session / "report.pdf").stat().st_size > 10_000
    header = (session / "positions.csv").read_text().splitlines()[0]
    assert header.startswith("index,run,direction,target_x_mm,target_y_mm,measured_x_mm")
    tc = results["truth_comparison"]
    # the estimate agrees with the simulator's truth within its own error bars
    assert tc["position_rms_error_um"] < 3.0 * tc["mean_sigma_um"]
    assert 0.2 < tc["z_mean_square"] < 3.0
    assert tc["straightness_x_um"] is not None and tc["straightness_y_um"] is not None


def test_summary_lines_print_results_json_beside_its_truth(quick_planar_demo):
    results = json.loads((quick_planar_demo / "session" / "results.json").read_text())
    lines = planar_summary_lines(results)
    pl, tc = results["figures"]["planar"], results["truth_comparison"]
    square = next(line for line in lines if line.startswith("squareness"))
    assert f"{pl['squareness_urad']:+.1f} \u00b1 {pl['squareness_sigma_urad']:.1f}" in square
    assert f"truth {tc['squareness_urad']:+.1f}" in square
    scale_y = next(line for line in lines if line.startswith("scale Y"))
    assert f"truth {tc['scale_y_ppm']:+.1f} ppm" in scale_y
    assert any(f"truth {tc['straightness_y_um']:.2f}" in line for line in lines)
