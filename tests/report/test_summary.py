"""The report's text rows come from results.json and the spec, never from elsewhere."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.report.pages.summary import (
    extremes_rows,
    fmt,
    intrinsics_rows,
    iso_rows,
    outlier_rows,
    position_table,
    spec_checks,
    summary_rows,
    title_rows,
    truth_rows,
)
from tests.report.conftest import make_results

SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


def test_summary_rows_print_the_results_figures():
    results, _ = make_results()
    rows = {r.name: r for r in summary_rows(results)}
    single = results["figures"]["single_run"]
    assert rows["Scale error"].value == single["scale_ppm"] and rows["Scale error"].unit == "ppm"
    assert rows["Mean step"].value == single["mean_step_mm"] and rows["Mean step"].text() == f"{single['mean_step_mm']:.6f}"
    assert rows["Periodic error period"].value == single["periodic_period_mm"]
    assert not any(name.startswith("Truth") for name in rows)  # truth has its own page
    assert {r.name: r.value for r in truth_rows(results)}["Truth: position error RMS"] == 0.5
    U = results["uncertainty"]["figures_k2"]
    assert rows["ISO 230-2 Accuracy A (bidirectional)"].u_k2 == U["A_um"] == results["uncertainty"]["expanded_k2_um"]
    assert rows["ISO 230-2 Repeatability R (bidirectional)"].u_k2 == U["R_um"] < U["A_um"]
    assert rows["Max |deviation|"].u_text().startswith("\u00b1 ")
    iso = results["figures"]["iso230_2"]
    assert rows["ISO 230-2 Accuracy A (bidirectional)"].value == iso["A_um"]
    assert rows["ISO 230-2 Repeatability R (backward \u2193)"].value == iso["R_down_um"]


def test_extremes_are_peak_to_valley_and_max_abs_without_outliers():
    results, _ = make_results()
    for i, r in enumerate(results["positions"]):
        r["straightness_um_1"] = float(i)
        r["yaw_urad"] = -float(i)
    results["positions"][-1]["outlier"] = True  # its extreme value must not count
    rows = {r.name: r.value for r in extremes_rows(results)}
    n = len(results["positions"])
    assert rows["Max straightness v1 (peak-to-valley)"] == n - 2
    assert rows["Max |yaw|"] == n - 2


def test_iso_rows_in_A_R_E_B_M_order_per_direction():
    iso = {"n_targets": 12, "E_up_um": 3.0, "E_um": 4.0, "A_um": 12.0, "A_down_um": None, "R_up_um": 2.0,
           "B_mean_um": 1.5, "per_target": {"R_um": [1.0]}, "notes": ["x"], "Q_um": 7.0}
    rows = [(r.name, r.value) for r in iso_rows(iso)]
    assert rows == [("ISO 230-2 Accuracy A (bidirectional)", 12.0), ("ISO 230-2 Repeatability R (forward \u2191)", 2.0),
                    ("ISO 230-2 Systematic deviation E (bidirectional)", 4.0),
                    ("ISO 230-2 Systematic deviation E (forward \u2191)", 3.0),
                    ("ISO 230-2 Reversal error B (mean)", 1.5), ("ISO 230-2 Q", 7.0)]
    assert iso_rows(None) == []


def test_spec_checks_pass_and_fail_against_the_limits():
    results, _ = make_results()
    iso = results["figures"]["iso230_2"]
    checks = spec_checks(results, SPEC)
    assert [c.name for c in checks][:1] and all(c.passed is not None for c in checks)
    acc = checks[0]
    assert np.isclose(acc.measured, iso["A_um"] / 2) and acc.passed == (iso["A_um"] / 2 <= 20)
    results["figures"]["straightness_um_max"] = 3.0
    tight = spec_checks(results, {"accuracy_um": 0.01, "straightness_um": 1.0})
    assert [c.passed for c in tight] == [False, False]
    assert spec_checks(results, None) == []


def test_fmt_significant_digits_and_dash():
    assert fmt(12.3456) == "12.3" and fmt(0.0012345) == "0.00123" and fmt(None) == "\u2014"
    assert fmt(float("nan")) == "\u2014" and fmt(0) == "0" and fmt(2.0001, 7) == "2.000100"
    assert fmt(6.47e-12) == "0" and fmt(-3e-11) == "0"  # rounding noise of a difference reads 0


def test_position_table_has_one_row_per_position_in_index_order():
    results, _ = make_results()
    header, rows, widths = position_table(results)
    assert len(rows) == len(results["positions"]) and len(header) == len(rows[0]) == len(widths)
    assert sum(widths) <= 180  # A4 minus margins
    assert not any("truth" in h for h in header)
    results["positions"][3]["truth_deviation_um"] = 1.234
    header, rows, widths = position_table(results)
    assert rows[3][header.index("truth dev.\n[\u00b5m]")] == "1.23" and sum(widths) <= 180
    assert rows[5][-1] == "yes" and rows[4][-1] == ""
    dev_col = header.index("deviation\n[\u00b5m]")
    assert float(rows[3][dev_col]) == round(results["positions"][3]["deviation_um"], 2)
    # the table's sigma is the one the bands draw (sigma_total_um 0.8), not the noise alone (0.5): issue 35
    assert rows[3][header.index("1\u03c3\n[\u00b5m]")] == "0.80"


def test_title_block_and_intrinsics():
    results, _ = make_results()
    meta = {"camera": {"name": "cam A", "lens": "8 mm"}, "stage": {"name": "LPS-400", "controller": "GRBL 1.1"}}
    rows = dict(title_rows(meta, results, "9.9"))
    assert rows["Software"] == "lps-calib 9.9" and rows["Lens"] == "8 mm" and rows["Controller"] == "GRBL 1.1"
    assert "9\u00d76" in rows["Board"] and "20.00 mm" in rows["Board"]
    assert rows["Session hash"].startswith("sha256 abab")
    intr = {name: (v, s) for name, v, s in intrinsics_rows(results)}
    assert intr["fx"] == ("600.000 px", "0.50 px") and intr["k2"][1] == "\u2014"


def test_outlier_rows_merge_positions_and_flags():
    results, _ = make_results()
    rows = outlier_rows(results)
    assert [r["index"] for r in rows] == [5]
    assert "RMS 2.1 px" in rows[0]["reason"] and rows[0]["file"] == "images/00005.png"


def test_figure_notes_are_collected_once():
    from lps_gui.report.pages.summary import figure_notes

    results, _ = make_results()
    results["figures"]["single_run"]["notes"] = ["a", "b"]
    results["figures"]["iso230_2"]["notes"] = ["b", "c"]
    assert figure_notes(results) == ["a", "b", "c"]


def test_class_names_are_printed_as_words_and_identification_is_shown():
    results, _ = make_results()
    meta = {"stage": {"driver": "RigStage", "axis": "X"}, "camera": {"driver": "SimulatedCamera"},
            "identification": {"operator": "A. Meier", "customer": "ACME", "stage_serial": "SN 42"}}
    rows = dict(title_rows(meta, results, "1"))
    assert rows["Stage"] == "simulated stage, serial SN 42, axis X" and rows["Camera"].startswith("simulated camera")
    assert rows["Operator"] == "A. Meier" and rows["Customer"] == "ACME"
    assert dict(title_rows({"stage": {"driver": "GrblStage"}}, results, "1"))["Stage"] == "grbl stage"


def test_verdict_decision_rule_and_indicative_runs():
    from lps_gui.report.pages.verdict import INDICATIVE_COLOR, verdicts

    results, _ = make_results()
    iso = results["figures"]["iso230_2"]
    U = results["uncertainty"]["figures_k2"]["A_um"]
    a_half = iso["A_um"] / 2
    # limit well above: PASS, indicative with 2 runs (never green without 5 runs, never red)
    far = verdicts(results, {"accuracy_um": a_half + U})[0]
    assert far.verdict == "PASS (indicative)" and far.color == INDICATIVE_COLOR and far.u_k2 == U / 2
    # limit inside the uncertainty zone: not resolved
    near = verdicts(results, {"accuracy_um": a_half + U / 4})[0]
    assert near.verdict == "not resolved"
    below = verdicts(results, {"accuracy_um": a_half - U / 4})[0]
    assert below.verdict == "not resolved"
    # with 5 runs per direction the same figures give a full verdict
    results["figures"]["per_run"] = [{"run": r, "direction": d} for r in range(1, 6) for d in "+-"]
    assert verdicts(results, {"accuracy_um": a_half + U})[0].verdict == "PASS"
    fail = verdicts(results, {"accuracy_um": (a_half - U / 2) / 2})[0]
    assert fail.verdict == "FAIL" and fail.color == "#c00000"
    assert verdicts(results, None) == []


@pytest.mark.parametrize("env, why", [({}, "board temperature and expansion coefficient not recorded"),
                                      ({"board_temperature_c": 21.0}, "board expansion coefficient not recorded"),
                                      ({"board_cte_ppm_per_k": 23.0}, "board temperature not recorded"),
                                      ({"board_temperature_c": 20.0, "board_cte_ppm_per_k": 23.0},
                                       "the board was at 20 \u00b0C")])
def test_no_thermal_correction_says_which_case_applies(env, why):
    from lps_gui.report.pages.budget import environment_rows

    rows = dict(environment_rows({**make_results()[0], "environment": env}))
    assert rows["Thermal correction applied"] == f"none: {why}"


def test_intrinsics_rows_list_a_rational_thin_prism_lens_terms():
    results, _ = make_results()
    assert [r[0] for r in intrinsics_rows(results)] == ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
    results["intrinsics"]["dist"] = [-0.1, 0.05, 0.0, 0.0, 0.01, 0.02, -0.01, 0.005, 1e-3, 0.0, 0.0, 0.0]
    rows = intrinsics_rows(results)
    assert [r[0] for r in rows[9:]] == ["k4", "k5", "k6", "s1"] and rows[9][2] == "held"
