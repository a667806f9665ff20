"""Simulated sessions check themselves (issue 35): a report its truth contradicts says so on page 1, in the console
and in results.json flags; one its truth agrees with says nothing."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.results.model import as_results
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pages.summary import outlier_rows, truth_check_lines
from lps_gui.sim.points import simulate_point_session
from lps_gui.sim.truth_figures import figure_checks, finding_checks, self_check


@pytest.fixture(scope="module")
def point_session(tmp_path_factory):
    """A small point-level session: 12 targets both ways, two runs (ISO 230-2 figures), the true intrinsics; corner
    noise 0.02 px, so the stage's repeatability, not the measurement's noise, makes R (at 0.2 px, R and A come out
    10-20 x the truth: benchmarks/honesty.py's finding, docs/validation.md)."""
    spec = small_spec(seed=3, views=12, directions="both", runs=2, noise_px=0.02)
    return simulate_point_session(spec, tmp_path_factory.mktemp("self-check") / "session"), spec


def test_a_session_its_truth_agrees_with_passes_and_has_no_flag(point_session):
    session, _ = point_session
    results = estimate_session(session.folder)
    check = results["truth_comparison"]["self_check"]
    assert check == {"passed": True, "problems": []}
    assert not [f for f in results["flags"] if f["kind"] == "truth_check"]
    assert truth_check_lines(results) == []
    names = {c["figure"] for c in figure_checks(results)}
    assert {"A", "E", "R", "B", "M", "scale", "max |deviation|"} <= names


def test_a_board_printed_off_scale_makes_the_truth_contradict_the_report_and_it_says_so(point_session, tmp_path):
    """The board's squares 0.5 % off what session.json says (an undeclared print error): every displacement is 0.5 %
    off, 110 um over the 22 mm travel against sigmas of a few um."""
    session, _ = point_session
    folder = tmp_path / "session"
    shutil.copytree(session.folder, folder)
    meta = json.loads((folder / "session.json").read_text())
    meta["board"]["square_mm"] *= 1.005
    (folder / "session.json").write_text(json.dumps(meta))
    results = estimate_session(folder)
    check = results["truth_comparison"]["self_check"]
    assert not check["passed"]
    assert any(p.startswith("per-stop positions: mean (error/sigma)^2") for p in check["problems"]), check
    flags = [f for f in results["flags"] if f["kind"] == "truth_check"]
    assert len(flags) == 1 and flags[0]["index"] is None and "truth contradicts" in flags[0]["message"]
    lines = truth_check_lines(results)  # page 1's red lines and the console's
    assert lines[0].startswith("SIMULATED SESSION FAILS ITS TRUTH CHECK") and len(lines) == 1 + len(check["problems"])
    assert all(r["index"] != -1 for r in outlier_rows(results))  # not a view: kept out of the outlier table

    from lps_gui.cli.estimate import format_summary

    assert "SIMULATED SESSION FAILS ITS TRUTH CHECK" in format_summary(as_results(results))

    from pypdf import PdfReader

    from lps_gui.report.pdf.document import write_report

    page1 = " ".join(PdfReader(str(write_report(folder, results))).pages[0].extract_text().split())
    assert "SIMULATED SESSION FAILS ITS TRUTH CHECK" in page1 and "per-stop positions: mean (error/sigma)^2" in page1


def _motion_results(resolved: bool, truth_urad: float) -> dict:
    """A hand-made results.json of one line with an EBX (pitch) profile called ``resolved``."""
    K = 6
    pos = [{"index": i, "run": 1, "direction": "+", "target_mm": float(i), "used": True, "truth_deviation_um": 0.0}
           for i in range(K)]
    true = [truth_urad * (i % 2) for i in range(K)]
    return {"positions": pos, "truth_comparison": {"z_mean_square": 1.0},
            "error_motions": {"motions": {"EBX": {"unit": "urad", "values": [0.0, 40.0, 0.0, 40.0, 0.0, 40.0],
                                                  "span_urad": 40.0, "sigma_urad": 15.0, "noise_span_urad": 20.0,
                                                  "resolved": resolved}},
                              "truth": {"EBX": {"true_values": true}}}}


def test_a_resolved_motion_the_truth_does_not_have_fails_the_check():
    false = self_check(_motion_results(True, 0.0))
    assert not false["passed"] and false["problems"] == [
        "EBX called resolved, but the truth is 0 (noise threshold 20)"]
    assert self_check(_motion_results(True, 40.0))["passed"]  # the truth has it: a true call
    assert self_check(_motion_results(False, 0.0))["passed"]  # not called: nothing claimed
    [row] = finding_checks(_motion_results(True, 0.0))
    assert row == {"finding": "EBX", "resolved": True, "truth": 0.0, "noise": 20.0, "truth_has_it": False,
                   "false": True}


def test_a_real_session_is_not_checked():
    assert self_check({"positions": [], "truth_comparison": None}) is None


def test_the_scales_truth_is_the_same_weighted_slope_the_estimate_takes():
    """The scale is a slope weighted by 1/sigma^2 (SPEC 5); on a profile that is not a line (a periodic error) the
    unweighted slope of the same truth differs (here 6 ppm, the two-depth flat stage's -7 ppm bias of every seed).
    An exact measurement must score zero error: its truth is reduced by the same weighted fit."""
    t = np.arange(13) * 25.0
    dev = 0.1 * t + 5.0 * np.sin(2 * np.pi * t / 8.0 + 0.3)  # 100 ppm and the flat stage's 5 um periodic error
    sigma = np.linspace(0.5, 1.1, t.size)
    sigma[0] = 0.0  # the reference capture (the gauge)
    w = 1.0 / np.where(sigma > 0, sigma, np.median(sigma[1:])) ** 2
    weighted = 1e3 * np.polyfit(t, dev, 1, w=np.sqrt(w))[0]  # polyfit weights multiply the residuals
    assert abs(weighted - 1e3 * np.polyfit(t, dev, 1)[0]) > 3.0  # the two slopes differ: the test has teeth
    positions = [{"used": True, "target_mm": float(x), "run": 1, "direction": "+", "truth_deviation_um": float(d),
                  "sigma_um": float(s)} for x, d, s in zip(t, dev, sigma)]
    results = {"positions": positions, "truth_comparison": {"z_mean_square": 1.0},
               "figures": {"single_run": {"scale_ppm": weighted, "max_abs_deviation_um": float(np.abs(dev).max())}},
               "uncertainty": {"figures_k2": {"scale_ppm": 2.0, "max_abs_deviation_um": 2.0}}}
    scale = next(c for c in figure_checks(results) if c["figure"] == "scale")
    assert abs(scale["error"]) < 1e-6, scale


def _settling_results(settling_time_s: float) -> dict:
    """A hand-made results.json of a settling test on a stage ringing 50 um at 8 Hz (true settling time 0.5675 s)."""
    pos = [{"index": i, "run": 1, "direction": "+", "target_mm": 0.0, "used": True, "truth_deviation_um": 0.0}
           for i in range(4)]
    return {"positions": pos, "truth_comparison": {"z_mean_square": 1.0},
            "asme_b5_64": {"settling": {"band_um": 5.0, "settling_time_s": settling_time_s, "settling_time_U_s": 0.08,
                                        "truth": {"settling_time_s": 0.5675}}}}


def test_a_settling_time_is_checked_against_the_stage_s_true_ringing():
    """The settling test's headline figure is scored like every other (the campaign's settling cells had none)."""
    [row] = [c for c in figure_checks(_settling_results(0.5275)) if c["figure"] == "settling time"]
    assert row["unit"] == "s" and row["truth"] == 0.5675 and row["U_k2"] == 0.08
    assert abs(row["z"] - (-1.0)) < 1e-9
    assert self_check(_settling_results(0.5275))["passed"]
    off = self_check(_settling_results(0.5675 + 0.2))  # 2.5 U late: the truth contradicts the report
    assert not off["passed"] and off["problems"][0].startswith("settling time 0.7675 s, truth 0.5675")
    assert not [c for c in figure_checks({**_settling_results(0.5), "asme_b5_64": {}}) if c["figure"] == "settling time"]
