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
from lps_gui.report.pages.verdict import verdicts
from lps_gui.sim.points import simulate_point_session

SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


@pytest.fixture(scope="module")
def estimated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("verdict") / "s"
    simulate_point_session(replace(small_spec(seed=3, views=12, directions="both", runs=2)), folder)
    meta = json.loads((folder / "session.json").read_text())
    meta["stage_spec"] = SPEC
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
