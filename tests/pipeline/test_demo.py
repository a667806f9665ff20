"""The demo's pieces: its folder handling, its experiment, its truth check and its fallbacks."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.simulate import simulate_views
from lps_gui.errors import InputError
from lps_gui.io.corners_vnl import read_corners_vnl
from lps_gui.io.session import Session
from lps_gui.pipeline import demo
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


def test_truth_errors_measure_the_noise_put_in():
    results, truth = make_results(runs=2)  # measured = truth + N(0, 0.5 um)
    te = demo.truth_errors(results, truth)
    assert 0.3 < te["rms_um"] < 1.0 and te["max_um"] < 3.0
    for r, s in zip(results["positions"], truth["positions_mm"]):
        r["deviation_um"] = (s + results["positions"][0]["target_mm"] - r["target_mm"]) * 1000.0
    assert demo.truth_errors(results, truth)["rms_um"] < 1e-6


def test_summary_is_five_lines_with_the_truth_check():
    results, truth = make_results(runs=2)
    spec = demo.demo_spec(quick=True)
    lines = demo.summary_lines(results, truth, spec)
    assert len(lines) == 5
    assert lines[-1].startswith("error against truth: position RMS")
    assert "PASS" in lines[3] or "FAIL" in lines[3]


def test_point_level_fallback_writes_corners_and_truth(tmp_path):
    spec = demo.demo_spec(quick=True)
    session = demo._point_session(spec, tmp_path / "s", spec.rig.intrinsics)
    again = Session.open(tmp_path / "s")
    table = read_corners_vnl(again.corners_path, spec.rig.board.n_corners)
    expected = simulate_views(spec).corners_px
    assert table.corners_px.shape == expected.shape
    assert np.allclose(np.nan_to_num(table.corners_px), np.nan_to_num(expected), atol=1e-3)
    assert len(again.records()) == spec.plan.n_frames() and again.truth["positions_mm"]
    assert session.folder == tmp_path / "s"


def test_capture_falls_back_and_says_so(tmp_path, monkeypatch):
    real = demo.available

    def without_images(module, name):
        return None if module in ("lps_gui.capture.sim_session", "lps_gui.pipeline.simulate_images",
                                  "lps_gui.pipeline.simulate_points") else real(module, name)

    monkeypatch.setattr(demo, "available", without_images)
    spec = demo.demo_spec(quick=True)
    session, has_images, message, status = demo.capture_step(tmp_path / "s", spec, spec.rig.intrinsics,
                                                             lambda *a: None, None)
    assert not has_images and status == "fallback" and "point-level" in message
    assert session.corners_path.exists()


def test_cancel_stops_the_demo_after_the_running_step(tmp_path, monkeypatch):
    from lps_gui.core.progress import CancelToken
    from lps_gui.errors import Cancelled

    _hide(monkeypatch, "lps_gui.pipeline.simulate_images", "lps_gui.pipeline.intrinsics")
    token = CancelToken()
    token.cancel()
    with pytest.raises(Cancelled):
        demo.run_demo(tmp_path / "out", quick=True, cancel=token)
    assert (tmp_path / "out" / demo.MARKER).exists()


def test_available_tells_absent_pieces_from_broken_ones():
    assert demo.available("lps_gui.no_such_module", "x") is None
    assert demo.available("lps_gui.core.plan", "Plan") is not None


def _hide(monkeypatch, *modules):
    real = demo.available
    monkeypatch.setattr(demo, "available", lambda module, name: None if module in modules else real(module, name))


@pytest.mark.gui
def test_point_level_demo_runs_to_the_report_and_says_what_it_skipped(tmp_path, monkeypatch):
    """Without the image pipeline and the capture engine the demo still ends in a report, and says so."""
    _hide(monkeypatch, "lps_gui.capture.sim_session", "lps_gui.pipeline.simulate_images", "lps_gui.pipeline.intrinsics")
    lines = []
    res = demo.run_demo(tmp_path / "out", quick=True, say=lines.append)
    status = {s.name: s.status for s in res.steps}
    assert status == {"intrinsics": "skipped", "capture": "fallback", "detect": "skipped", "estimate": "done",
                      "report": "done"}
    assert any("point-level" in line for line in lines) and any("image pipeline not installed" in line for line in lines)
    assert res.report_pdf.read_bytes().startswith(b"%PDF")
    assert {p.name for p in res.csvs} == {"positions.csv", "summary.csv"}
    assert len(res.summary) == 5
    # point-level corners with 0.2 px noise: the positions match the simulator's truth within a few sigma
    te = demo.truth_errors(res.results, Session.open(res.session_dir).truth)
    assert te["rms_um"] < 4 * te["median_sigma_um"] + 1.0


@pytest.mark.slow
def test_quick_demo_end_to_end_through_images(tmp_path):
    """`lps demo --quick`: intrinsics set, capture engine, detection, estimate, report; the truth check holds."""
    res = demo.run_demo(tmp_path / "out", quick=True)
    assert [s.status for s in res.steps] == ["done"] * 5, res.steps
    assert res.report_pdf.exists() and (res.out_dir / "intrinsics.json").exists()
    te = demo.truth_errors(res.results, Session.open(res.session_dir).truth)
    assert te["rms_um"] < 4 * te["median_sigma_um"] + 1.0


@pytest.mark.gui
def test_lps_demo_prints_paths_summary_and_what_it_skipped(tmp_path, monkeypatch, capsys):
    from lps_gui.cli import main

    _hide(monkeypatch, "lps_gui.capture.sim_session", "lps_gui.pipeline.simulate_images", "lps_gui.pipeline.intrinsics")
    assert main(["demo", "--quick", "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert f"report:  {tmp_path / 'd' / 'session' / 'report.pdf'}" in out
    assert "csv:     " in out and "error against truth: position RMS" in out
    assert "not the full chain: intrinsics: skipped" in out
    summary = [line for line in out.splitlines() if line.startswith("  ")]
    assert len(summary) == 5


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
    assert [s.status for s in res.steps] == ["done"] * 5, res.steps
    single = res.results["figures"]["single_run"]
    spec = demo.demo_spec(quick=False)
    assert abs(single["periodic_period_mm"] - spec.rig.errors.pitch_mm) < 0.2
    assert abs(single["periodic_amplitude_um"] - spec.rig.errors.periodic_um) < 1.5
    te = demo.truth_errors(res.results, Session.open(res.session_dir).truth)
    assert te["rms_um"] < 3.0
    assert elapsed < 300, f"demo took {elapsed:.0f} s (budget 5 minutes on 2 cores)"
