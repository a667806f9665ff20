"""Issue 37: the verdict, U (k = 2) and the decision rule are machine-readable, the same in results.json, summary.csv,
the report's rows and the PDF; an unresolved span says "not resolved" in summary.csv, never a bare number."""
import csv
import json
from dataclasses import replace

import pytest
from pypdf import PdfReader

from lps_gui.core.truth.simulate import small_spec
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pages.summary import summary_rows
from lps_gui.io.results.verdict_rows import session_verdicts as verdicts
from lps_gui.sim.points import simulate_point_session

SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


@pytest.fixture(scope="module")
def estimated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("verdict") / "s"
    simulate_point_session(replace(small_spec(seed=3, views=12, directions="both", runs=2)), folder)
    return estimate_with_spec(folder, SPEC)


def estimate_with_spec(folder, spec):
    """(folder, results, summary.csv rows by name) of the session estimated with ``spec`` as its stage_spec."""
    meta = json.loads((folder / "session.json").read_text())
    meta["stage_spec"] = spec
    (folder / "session.json").write_text(json.dumps(meta))
    results = estimate_session(folder)
    with open(folder / "summary.csv", newline="") as f:
        rows = {r["name"]: r for r in csv.DictReader(f)}
    return folder, results, rows


def test_summary_csv_carries_u_and_the_verdict_of_results_json(estimated):
    _folder, results, rows = estimated
    verdict = results["verdict"]
    assert verdict["decision_rule"].startswith("ISO 14253-1")
    assert rows["verdict"]["value"] == verdict["overall"] and verdict["overall"] in (
        "PASS", "FAIL", "not resolved", "FAIL (indicative)")
    assert rows["decision_rule"]["value"] == verdict["decision_rule"]
    report = verdicts(results, SPEC)
    assert [c["verdict"] for c in verdict["checks"]] == [v.verdict for v in report] and report
    for check, v in zip(verdict["checks"], report):
        row = rows[f"check_{check['key']}"]
        assert row["note"].startswith(v.verdict)
        assert float(row["value"]) == pytest.approx(v.measured, rel=1e-5)
        if v.u_k2 is not None:
            assert float(row["u_k2"]) == pytest.approx(v.u_k2, rel=1e-5)
    # every figure the report prints with a U has the same U in summary.csv
    shown = [r for r in summary_rows(results) if r.u_k2 is not None]
    assert shown
    for r in shown:
        assert float(rows[r.key]["u_k2"]) == pytest.approx(r.u_k2, rel=1e-5), r.key


def test_an_unresolved_span_says_not_resolved(estimated):
    _folder, results, rows = estimated
    angles = results["figures"]["angles_resolution"]
    unresolved = [n for n in ("roll", "pitch", "yaw") if not angles[n]["resolved"]]
    assert unresolved  # one planar board: the tilts are not resolved (SPEC 11)
    for name in unresolved:
        row = rows[f"{name}_span"]
        assert row["value"] == "" and row["note"].startswith("not resolved"), row


@pytest.mark.gui
def test_the_pdf_prints_the_verdict_results_json_states(estimated):
    from lps_gui.report.pdf.document import write_report

    folder, results, _rows = estimated
    path = write_report(folder, results)
    text = " ".join(PdfReader(path).pages[0].extract_text().split())
    for check in results["verdict"]["checks"]:
        assert check["verdict"] in text


PLANAR_SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38, "squareness_urad": 50}


@pytest.fixture(scope="module")
def planar_estimated(tmp_path_factory):
    from lps_gui.cli import main as lps_main

    folder = tmp_path_factory.mktemp("planar-verdict") / "s"
    assert lps_main(["simulate", "--planar", "--points", str(folder), "--preset", "small-planar", "--directions",
                     "both", "--runs", "2", "--seed", "3"]) == 0
    return estimate_with_spec(folder, PLANAR_SPEC)


def test_a_planar_session_states_its_verdict_u_and_rule_per_axis_and_for_squareness(planar_estimated):
    """Issue 37: a planar session's results.json and summary.csv carry the verdict page 1 prints: each axis's rows,
    the squareness row against the stage_spec's squareness_urad, U (k = 2) and the decision rule."""
    from lps_gui.report.pages.planar import planar_summary_rows

    _folder, results, rows = planar_estimated
    verdict = results["verdict"]
    assert verdict["decision_rule"].startswith("ISO 14253-1") and rows["decision_rule"]["value"] == verdict["decision_rule"]
    assert rows["verdict"]["value"] == verdict["overall"] != "no specification"
    report = verdicts(results, PLANAR_SPEC)
    names = [c["name"] for c in verdict["checks"]]
    assert names == [v.name for v in report]
    assert {"X: Positional accuracy", "Y: Positional accuracy", "X: Repeatability", "Squareness"} <= set(names)
    for check, v in zip(verdict["checks"], report):
        row = rows[f"check_{check['key']}"]
        assert check["verdict"] == v.verdict and row["note"].startswith(v.verdict)
        assert v.measured is not None and float(row["value"]) == pytest.approx(v.measured, rel=1e-5)
        assert v.u_k2 is not None and float(row["u_k2"]) == pytest.approx(v.u_k2, rel=1e-5)
    # the squareness row compares |squareness| with the U page 1's geometry table prints
    square = next(r for r in planar_summary_rows(results) if r.key == "squareness_urad")
    check = next(c for c in verdict["checks"] if c["name"] == "Squareness")
    assert check["measured"] == pytest.approx(abs(square.value)) and check["u_k2"] == pytest.approx(square.u_k2)
    assert float(rows["squareness"]["u_k2"]) == pytest.approx(square.u_k2, rel=1e-5)
    # every planar figure printed with a U has that U in summary.csv
    shown = [r for r in planar_summary_rows(results) if r.u_k2 is not None and not r.unresolved]
    assert len(shown) >= 6  # squareness (2), scales (2), ISO A/R... per axis
    csv_name = {"squareness_urad": "squareness", "scale_x_ppm": "scale_x", "scale_y_ppm": "scale_y"}
    for r in shown:
        assert float(rows[csv_name.get(r.key, r.key)]["u_k2"]) == pytest.approx(r.u_k2, rel=1e-5), r.key


def test_a_planar_axis_verdict_uses_that_axis_budget(planar_estimated):
    _folder, results, _rows = planar_estimated
    per_axis = results["uncertainty"]["per_axis"]
    for axis in "XY":
        check = next(c for c in results["verdict"]["checks"] if c["name"] == f"{axis}: Positional accuracy")
        assert check["u_k2"] == pytest.approx(0.5 * per_axis[axis]["figures_k2"]["A_um"], rel=1e-9)  # U(A/2)


@pytest.mark.gui
def test_the_planar_pdf_and_the_gui_print_the_verdict_results_json_states(planar_estimated, qtbot):
    from lps_gui.gui.results.panel import verdict_html
    from lps_gui.io.results.model import as_results
    from lps_gui.report.pdf.document import write_report

    folder, results, _rows = planar_estimated
    text = " ".join(PdfReader(write_report(folder, results)).pages[0].extract_text().split())
    html = verdict_html(as_results(results), PLANAR_SPEC)
    for check in results["verdict"]["checks"]:
        assert f"{check['name']} " in text and check["name"] in html
    assert results["verdict"]["overall_text"] in text and results["verdict"]["overall_text"] in html
