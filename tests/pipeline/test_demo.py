"""The demo's pieces: its folder handling, its experiment, its truth check, its printed summary."""
from __future__ import annotations

import json
import re

import pytest

from lps_gui.errors import InputError
from lps_gui.pipeline.demos import run as demo
from lps_gui.pipeline.demos import summary as demo_summary
from tests.report.conftest import make_results


def test_out_folder_is_cleared_only_when_the_demo_made_it(tmp_path):
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    with pytest.raises(InputError, match="not made by `lps demo`"):
        demo.prepare_out(foreign)
    assert (foreign / "thesis.tex").read_text() == "precious"
    mine = tmp_path / "mine"
    demo.prepare_out(mine)
    (mine / "session").mkdir()
    (mine / "old.txt").write_text("x")
    demo.prepare_out(mine)
    assert [p.name for p in mine.iterdir()] == [demo.MARKER]


def test_demo_experiments_are_bidirectional_with_two_runs():
    full = demo.demo_spec(quick=False)
    assert full.rig.intrinsics.image_size == (1920, 1080) and (full.rig.board.cols, full.rig.board.rows) == (30, 18)
    assert full.plan.directions == "both" and full.plan.runs >= 2
    assert full.rig.errors.periodic_um > 0 and full.rig.errors.backlash_um > 0
    # the lead-screw pitch must be resolved by the target spacing (Nyquist)
    assert full.plan.step_mm < full.rig.errors.pitch_mm / 2
    assert full.plan.n_frames() <= 240  # the 5-minute budget on 2 cores
    quick = demo.demo_spec(quick=True)
    assert quick.plan.directions == "both" and quick.plan.runs >= 2 and quick.rig.intrinsics.image_size[0] <= 640


def test_truth_errors_are_results_truth_comparison():
    """The printed error against truth is results.json's truth_comparison, not a second reduction."""
    results, _ = make_results(runs=2)
    results["truth_comparison"] = {"position_rms_error_um": 0.61, "position_max_abs_error_um": 1.7, "median_sigma_um": 0.4}
    assert demo_summary.truth_errors(results) == {"rms_um": 0.61, "max_um": 1.7, "median_sigma_um": 0.4}
    assert demo_summary.truth_errors({**results, "truth_comparison": {}}) is None


def test_summary_is_five_lines_with_the_truth_check():
    results, _ = make_results(runs=2)
    results["truth_comparison"] = {"position_rms_error_um": 0.61, "position_max_abs_error_um": 1.7, "median_sigma_um": 0.4}
    spec = demo.demo_spec(quick=True)
    lines = demo_summary.summary_lines(results, spec)
    assert len(lines) == 5
    assert lines[-1].startswith("error against truth: position RMS")
    assert "PASS" in lines[3] or "FAIL" in lines[3]


def test_cancel_stops_the_demo_after_the_running_step(tmp_path):
    from lps_gui.core.progress import CancelToken
    from lps_gui.errors import Cancelled

    token = CancelToken()
    token.cancel()
    with pytest.raises(Cancelled):
        demo.run_demo(tmp_path / "out", quick=True, cancel=token)
    assert (tmp_path / "out" / demo.MARKER).exists()


DEMO_STEPS = ("intrinsics", "capture", "detect", "estimate", "report", "compensate")


@pytest.mark.slow
def test_quick_demo_end_to_end_through_images(tmp_path):
    """`lps demo --quick`: intrinsics set, capture engine, detection, estimate, report; the truth check holds."""
    res = demo.run_demo(tmp_path / "out", quick=True)
    assert [(s.name, s.status) for s in res.steps] == [(n, "done") for n in DEMO_STEPS], res.steps
    assert res.report_pdf.exists() and (res.out_dir / "intrinsics.json").exists()
    te = demo_summary.truth_errors(res.results)
    assert te["rms_um"] < 4 * te["median_sigma_um"] + 1.0


@pytest.mark.slow
def test_lps_demo_prints_the_truth_comparison_of_results_json(tmp_path, capsys):
    """`lps demo --quick`: paths, the summary lines, and the truth error exactly as results.json has it."""
    from lps_gui.cli import main
    assert main(["demo", "--quick", "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert f"report:  {tmp_path / 'd' / 'session' / 'report.pdf'}" in out and "csv:     " in out
    assert "not the full chain" not in out
    summary = [line for line in out.splitlines() if line.startswith("  ") and not line.startswith("    ")]
    truth_line = [line for line in summary if line.startswith("  error against truth")]
    assert len(summary) == 8 and len(truth_line) == 1  # 5 measurement lines, then the compensation pass
    tc = json.loads((tmp_path / "d" / "session" / "results.json").read_text())["truth_comparison"]
    printed = re.search(r"position RMS ([-\d.]+) \u00b5m, max ([-\d.]+) \u00b5m \(median 1-sigma ([-\d.]+)", truth_line[0])
    assert printed.groups() == (f"{tc['position_rms_error_um']:.2f}", f"{tc['position_max_abs_error_um']:.2f}",
                                f"{tc['median_sigma_um']:.2f}")
    plane = re.search(r"at the board plane RMS ([-\d.]+) \u00b5m", truth_line[0])
    assert plane.group(1) == f"{tc['board_plane_rms_error_um']:.2f}"


def test_lps_demo_refuses_a_foreign_folder(tmp_path, capsys):
    from lps_gui.cli import main
    (tmp_path / "notes.txt").write_text("mine")
    assert main(["demo", "--quick", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "not made by `lps demo`" in err and len(err.splitlines()) == 1
    assert (tmp_path / "notes.txt").read_text() == "mine"


@pytest.mark.slow
def test_full_demo_on_the_paper_rig(tmp_path):
    """`make demo`'s run: every step through images; the stage's lead-screw pitch and the truth are recovered."""
    import time

    t0 = time.monotonic()
    res = demo.run_demo(tmp_path / "out", quick=False)
    elapsed = time.monotonic() - t0
    assert [(s.name, s.status) for s in res.steps] == [(n, "done") for n in DEMO_STEPS], res.steps
    single = res.results.figures.single_run
    spec = demo.demo_spec(quick=False)
    assert abs(single.periodic_period_mm - spec.rig.errors.pitch_mm) < 0.2
    assert abs(single.periodic_amplitude_um - spec.rig.errors.periodic_um) < 1.5
    te = demo_summary.truth_errors(res.results)
    assert te["rms_um"] < 3.0
    assert elapsed < 300, f"demo took {elapsed:.0f} s (budget 5 minutes on 2 cores)"


def test_the_travel_demo_is_bidirectional_against_the_papers_table_1():
    """Issue 37: `lps demo --travel 1524` had no ISO 230-2 figures and no verdict (no spec, one direction)."""
    from lps_gui.pipeline.demos.targets import row_demo_spec

    assert row_demo_spec(1524.0, None).plan.directions == "both"  # ISO 230-2's bidirectional figures


def test_the_row_demo_states_its_verdict_against_the_papers_table_1(tmp_path):
    from lps_gui.pipeline.demos.run import run_demo
    from lps_gui.pipeline.demos.summary import PAPER_SPEC

    res = run_demo(tmp_path / "row", quick=True, preset="small-row")
    assert res.results.session_meta["stage_spec"] == PAPER_SPEC
    checks = res.results.raw["verdict"]["checks"]
    assert [c["name"] for c in checks] == ["Positional accuracy", "Repeatability", "Straight-line accuracy"]
    assert any(line.startswith("verdict (ISO 14253-1)") for line in res.summary)
