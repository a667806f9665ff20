"""The report's text rows come from results.json and the spec, never from elsewhere."""
from __future__ import annotations

import numpy as np

from lps_gui.report.summary import (extremes_rows, fmt, intrinsics_rows, iso_rows, outlier_rows, position_table,
                                    spec_checks, summary_rows, title_rows)
from tests.report.conftest import make_results

SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


def test_summary_rows_print_the_results_figures():
    results, _ = make_results()
    rows = {r.name: r for r in summary_rows(results)}
    single = results["figures"]["single_run"]
    assert rows["Scale error"].value == single["scale_ppm"] and rows["Scale error"].unit == "ppm"
    assert rows["Mean step"].value == single["mean_step_mm"] and rows["Mean step"].text() == "2.000100"
    assert rows["Periodic error period"].value == single["periodic_period_mm"]
    assert rows["Truth: position rms error"].value == 0.5


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


def test_iso_rows_flatten_per_direction():
    rows = iso_rows({"forward": {"E_um": 3.0}, "A_um": 12.0, "R_up_um": 2.0})
    names = {r.name: r.value for r in rows}
    assert names == {"forward \u2191: Systematic deviation E": 3.0, "Accuracy A": 12.0, "Repeatability R (up)": 2.0}
    assert iso_rows(None) == []


def test_spec_checks_pass_and_fail_against_the_limits():
    results, _ = make_results()
    checks = {c.name: c for c in spec_checks(results, SPEC)}
    acc = checks["Positional accuracy"]
    assert acc.measured is not None and acc.passed == (acc.measured <= 20)
    tight = {c.name: c for c in spec_checks(results, {"accuracy_um": 0.01, "straightness_um": -1})}
    assert tight["Positional accuracy"].passed is False
    assert tight["Straight-line accuracy"].passed is False
    assert spec_checks(results, None) == []


def test_accuracy_check_uses_the_two_sigma_envelope():
    results, _ = make_results(runs=2)
    for r in results["positions"]:
        r["deviation_um"] = 0.0
        r["outlier"] = False
    results["positions"][0]["deviation_um"] = 10.0  # target 0 forward: runs 10 and 0 -> mean 5, s 7.07
    acc = next(c for c in spec_checks(results, {"accuracy_um": 20}))
    assert np.isclose(acc.measured, 5.0 + 2 * np.std([10.0, 0.0], ddof=1))


def test_fmt_significant_digits_and_dash():
    assert fmt(12.3456) == "12.3" and fmt(0.0012345) == "0.00123" and fmt(None) == "\u2014"
    assert fmt(float("nan")) == "\u2014" and fmt(0) == "0" and fmt(2.0001, 7) == "2.000100"


def test_position_table_has_one_row_per_position_in_index_order():
    results, _ = make_results()
    header, rows = position_table(results)
    assert len(rows) == len(results["positions"]) and len(header) == len(rows[0])
    assert rows[5][-1] == "yes" and rows[4][-1] == ""
    dev_col = header.index("deviation\n[\u00b5m]")
    assert float(rows[3][dev_col]) == round(results["positions"][3]["deviation_um"], 2)


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
