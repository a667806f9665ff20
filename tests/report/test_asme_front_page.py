"""Issue 37: an ASME test session's verdict carries the test's own result, the same on page 1, in results.json,
summary.csv and the console; a step is never both achieved and stuck."""
import csv

import pytest
from pypdf import PdfReader

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module", params=["min-step", "settling"])
def demo(request):
    # one demo of each test per run (tests/conftest.py): the GUI's section tabs and test_every_figure_once read them too
    return request.param, request.getfixturevalue({"min-step": "min_step_demo", "settling": "settling_demo"}[request.param])


def test_the_test_result_is_one_row_everywhere(demo):
    test, res = demo
    name, word = {"min-step": ("Minimum incremental motion", "FAIL"), "settling": ("Settling time", "PASS")}[test]
    checks = {c["name"]: c for c in res.results["verdict"]["checks"]}
    assert checks[name]["verdict"] == word  # the demo's stage has a 3 um dead band / settles in 0.57 s of 1 s
    with open(res.session_dir / "summary.csv", newline="") as f:
        rows = {r["name"]: r for r in csv.DictReader(f)}
    key = "check_" + checks[name]["key"]
    assert rows[key]["note"].startswith(word)
    front = " ".join(PdfReader(res.report_pdf).pages[0].extract_text().split())
    assert name in front and f"{name} " in front
    title = {"min-step": "Minimum incremental motion test (ASME B5.64)", "settling": "Settling time test (ASME B5.64)"}
    assert title[test] in front  # a test-specific front page
    line = [s for s in res.summary if s.startswith(f"Verdict {name}")]
    assert line and f": {word} " in line[0]
    assert [r for r in res.summary if r.startswith(f"TUR {name}")].__len__() == 1  # one TUR row, not two
    if test == "min-step":
        assert "step = > 2.00" in front  # the bound, not a dash
        steps = res.results["asme_b5_64"]["incremental_step"]["steps"]
        assert not any(s["achieved"] and s["stuck"] for s in steps)
