"""Every figure produced once (issue 37): for each kind of session the demos make, every figure page 1 or 2 prints
is the same number with the same U (k = 2) in the PDF's tables, summary.csv, results.json and the GUI's results
panel, and the verdict rows are the same in all four.

Line sessions are pinned in tests/pipeline/test_machine_verdict.py and ASME min-step/settling in
tests/report/test_asme_front_page.py; here: planar, a row of targets, two depths, settling, as-left (compensated),
stitched and the light field's measurement, each through the one check :func:`assert_one_figure_everywhere`.
"""
from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import pytest

from lps_gui.io.results.model import as_results
from lps_gui.io.results.verdict_rows import session_verdicts as verdicts
from lps_gui.pipeline.results.verdict import CSV_NAMES
from lps_gui.report.pages.planar import planar_summary_rows
from lps_gui.report.pages.summary import summary_rows

pytestmark = pytest.mark.gui


# ----------------------------------------------------------------------------- sessions, one per kind


def _planar(tmp: Path, demo_out: Path) -> Path:
    from lps_gui.pipeline.estimate import estimate_session

    shutil.copytree(demo_out, tmp / "planar")  # the run's one quick planar demo (tests/conftest.py): estimated again here
    folder = tmp / "planar" / "session"
    _with_spec(folder, {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38, "squareness_urad": 50})
    estimate_session(folder)  # the demo gives no specification: the verdict rows need one
    return folder


def _row(tmp: Path) -> Path:
    from lps_gui.pipeline.estimate import estimate_session
    from tests.pipeline.test_estimate_targets import point_session

    session, _ = point_session(tmp / "row")
    _with_spec(session.folder, {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38})
    estimate_session(session.folder)
    return session.folder


def _two_depth(tmp: Path) -> Path:
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.truth.two_depth import two_depth_spec
    from lps_gui.pipeline.estimate import estimate_session
    from lps_gui.sim.points import simulate_point_session

    folder = tmp / "two-depth"
    simulate_point_session(two_depth_spec(seed=1, plan=Plan(start_mm=0.0, stop_mm=300.0, step_mm=10.0,
                                                            directions="both", runs=2)), folder)
    _with_spec(folder, {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38})
    estimate_session(folder)
    return folder


def _settling(tmp: Path, demo) -> Path:
    shutil.copytree(demo.session_dir, tmp / "settling")  # the run's one settling demo (tests/conftest.py): reported here
    return tmp / "settling"


def _as_left(tmp: Path) -> Path:
    from lps_gui.pipeline.demos.run import run_demo

    res = run_demo(tmp / "demo", quick=True)
    return res.reports[0].parent  # the compensated (as-left) session: its report is the demo's second PDF


def _stitched(tmp: Path) -> Path:
    from lps_gui.pipeline.estimate import estimate_session
    from tests.pipeline.test_stitched_estimate import stitched_session

    session, _, _ = stitched_session(tmp / "stitched", seed=0, segment_stops=13, travel_mm=254.0)
    estimate_session(session.folder)
    return session.folder


def _light_field(tmp: Path, lightfield_demo) -> Path:
    return lightfield_demo.measurement


KINDS = {"planar": _planar, "row of targets": _row, "two depths": _two_depth, "settling": _settling,
         "as left": _as_left, "stitched": _stitched, "light field": _light_field}
SHARED = {"planar": "quick_planar_demo", "settling": "settling_demo", "light field": "lightfield_demo"}  # tests/conftest.py


def _with_spec(folder: Path, spec: dict) -> None:
    meta = json.loads((folder / "session.json").read_text())
    meta["stage_spec"] = spec
    (folder / "session.json").write_text(json.dumps(meta))


@pytest.fixture(scope="module", params=list(KINDS))
def session(request, tmp_path_factory):
    tmp = tmp_path_factory.mktemp(request.param.replace(" ", "-"))
    if request.param in SHARED:
        return request.param, KINDS[request.param](tmp, request.getfixturevalue(SHARED[request.param]))
    return request.param, KINDS[request.param](tmp)


# ----------------------------------------------------------------------------- the one check


def _csv_rows(folder: Path) -> dict[str, dict[str, str]]:
    with open(folder / "summary.csv", newline="") as f:
        return {r["name"]: r for r in csv.DictReader(f)}


def _close(text: str, value: float | None) -> bool:
    if value is None:
        return text == ""
    return text != "" and math.isclose(float(text), float(value), rel_tol=1e-5, abs_tol=1e-9)


def _report_rows(results) -> list:
    if results.planar:
        return [r for r in planar_summary_rows(results) if r.key]
    return [r for r in summary_rows(results) if r.key]


def _csv_name(results, key: str) -> str:
    return CSV_NAMES.get(key, key) if results.planar else key


def assert_one_figure_everywhere(folder: Path, gui_rows: list[list[str]], gui_verdict: str) -> None:
    """results.json, summary.csv, the PDF's tables and the GUI's rows state each figure and verdict row alike."""
    from lps_gui.report.pdf.document import render_report

    doc = json.loads((folder / "results.json").read_text())
    results = as_results(doc)
    rows = _csv_rows(folder)
    # summary.csv is results.json's ``summary``, row by row
    assert [r[0] for r in doc["summary"]] == list(rows)
    info = render_report(folder)
    assert info.clipped == ()
    cells = [t.text for t in info.texts if t.where == "table"]
    spec = (doc.get("session_meta") or {}).get("stage_spec")
    checks = verdicts(results, spec)
    verdict_cells = {(v.name, v.measured_text()) for v in checks}
    report_rows = _report_rows(results)
    assert report_rows
    gui = {r[0]: r for r in gui_rows}
    for r in report_rows:
        name = _csv_name(results, r.key)
        row = rows.get(name)
        if r.value is None and not r.unresolved:  # a dash on the page: no row, or an empty one
            assert row is None or row["value"] == "", row
        elif r.unresolved:  # no value, no U: the note says why, in every file
            assert row is not None, f"{r.key}: printed, not in summary.csv"
            assert row["value"] == "" and row["u_k2"] == "" and row["note"] == r.unresolved.replace("\u00b5", "u"), row
        else:
            assert row is not None, f"{r.key}: printed, not in summary.csv"
            assert _close(row["value"], r.value), (name, row["value"], r.value)
            assert _close(row["u_k2"], r.u_k2), (name, row["u_k2"], r.u_k2)
        at = [i for i, c in enumerate(cells) if c == r.name and (c, cells[i + 1]) not in verdict_cells]
        assert at, f"{r.name!r} is not printed in the PDF's tables"
        for i in at:  # every page that prints it prints the same value and U
            assert cells[i + 1:i + 3] == [r.text(), r.u_text()], (r.name, cells[i + 1:i + 3])
        assert gui[r.name][1:3] == [r.text(), r.u_text()], (r.name, gui[r.name])
    verdict = doc.get("verdict") or {}
    assert [c["name"] for c in verdict.get("checks") or []] == [v.name for v in checks]
    if spec:
        assert rows["verdict"]["value"] == verdict["overall"] and rows["decision_rule"]["value"] == verdict["decision_rule"]
    for check, v in zip(verdict.get("checks") or [], checks):
        row = rows[f"check_{check['key']}"]
        assert check["verdict"] == v.verdict and row["note"].startswith(v.verdict)
        assert _close(row["value"], v.measured) and _close(row["u_k2"], v.u_k2), (v.name, row)
        i = cells.index(v.name)
        assert cells[i + 1] == v.measured_text() and cells[i + 5] == v.verdict, cells[i:i + 6]
        assert f"{v.name}: " in gui_verdict and v.verdict in gui_verdict


def _gui(qtbot, folder: Path) -> tuple[list[list[str]], str]:
    from lps_gui.gui.results.panel import ResultsPanel

    panel = ResultsPanel()
    qtbot.addWidget(panel)
    results = json.loads((folder / "results.json").read_text())
    with qtbot.waitSignal(panel.drawing_done, timeout=60000):
        panel.set_results(results, folder, folder)
    qtbot.waitUntil(lambda: not panel.drawing and panel.iso_table.rowCount() > 0, timeout=30000)
    table = panel.iso_table
    rows = [[table.item(r, c).text() if table.item(r, c) else "" for c in range(table.columnCount())]
            for r in range(table.rowCount())]
    return rows, panel.verdict.text()


def test_every_figure_is_one_number_with_one_u_in_every_file_and_the_gui(session, qtbot):
    _kind, folder = session
    gui_rows, gui_verdict = _gui(qtbot, folder)
    assert_one_figure_everywhere(folder, gui_rows, gui_verdict)
