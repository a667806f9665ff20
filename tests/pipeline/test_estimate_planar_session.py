"""A planar session from the shell's point of view: simulate, estimate, CSV per SPEC 10, report."""
from __future__ import annotations

import csv
import json

import pytest

from lps_gui.cli import main as lps_main
from lps_gui.io.results.document import PLANAR_POSITION_COLUMNS
from lps_gui.io.session import Session


@pytest.fixture(scope="module")
def planar_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("planar") / "s"
    rc = lps_main(["simulate", "--planar", "--points", str(folder), "--preset", "small-planar", "--directions", "both",
                   "--runs", "2", "--replaced", "9", "--seed", "3"])
    assert rc == 0
    assert lps_main(["estimate", str(folder)]) == 0
    return folder


def test_session_files_follow_spec_10(planar_session):
    s = Session.open(planar_session)
    assert s.planar and s.axes == ["X", "Y"]
    assert s.meta["stage"]["axes"] == ["X", "Y"]
    line = json.loads(s.captures_path.read_text().splitlines()[1])
    assert isinstance(line["target_mm"], list) and len(line["target_mm"]) == 2
    stops = list(s.plan().stops())
    assert len(stops) == len(s.records()) == 6 * 4 * 2 * 2


def test_positions_csv_has_exactly_the_planar_columns(planar_session):
    with open(planar_session / "positions.csv") as f:
        rows = list(csv.reader(f))
    assert tuple(rows[0]) == PLANAR_POSITION_COLUMNS
    assert len(rows) == 1 + 96


def test_results_carry_figures_planar_and_flag_the_replaced_view(planar_session):
    r = json.loads((planar_session / "results.json").read_text())
    pl = r["figures"]["planar"]
    for key in ("squareness_urad", "squareness_sigma_urad", "scale_x_ppm", "scale_x_sigma_ppm", "scale_y_ppm",
                "scale_y_sigma_ppm", "per_axis", "nodes"):
        assert key in pl
    assert r["axes"] == ["X", "Y"]
    assert len(pl["nodes"]) == 24 and all(n["error_um"] is not None for n in pl["nodes"])
    assert [f["index"] for f in r["flags"] if f["kind"] != "truth_check"] == [9]  # the truth check: issue 35
    tc = r["truth_comparison"]
    assert tc["flagged_outliers"] == [9] and tc["injected_outliers"] == [9]
    assert abs(tc["squareness_z"]) < 3.5
    assert tc["per_coordinate_rms_error_um"][0] < 2.0 * tc["mean_sigma_um"]


def test_planar_report_pages(planar_session):
    from lps_gui.report.pdf.document import render_report

    info = render_report(planar_session)
    text = [t for page in info.pages for t in page]
    assert "Axis geometry and per-axis figures (measured)" in text
    assert "Simulation only: against the simulator's truth" in text
    assert [t for t in text if t.startswith("figure:")] == ["figure:error_map", "figure:deviation_x", "figure:deviation_y",
                                                           "figure:straightness_x", "figure:straightness_y",
                                                           "figure:residuals"]
    assert info.path.stat().st_size > 10_000


def test_report_text_holds_squareness(planar_session):
    from lps_gui.report.pages.planar import planar_summary_rows

    r = json.loads((planar_session / "results.json").read_text())
    rows = {row.name: row for row in planar_summary_rows(r)}
    sq = rows["Squareness (angle +X to +Y minus 90\u00b0)"]
    assert sq.value == pytest.approx(r["figures"]["planar"]["squareness_urad"])
    k2 = (r.get("uncertainty") or {}).get("figures_k2") or {}
    assert sq.u_k2 == pytest.approx(k2.get("squareness_urad", 2 * r["figures"]["planar"]["squareness_sigma_urad"]))


def test_hybrid_on_a_planar_session_is_a_one_line_error(planar_session, capsys):
    rc = lps_main(["estimate", str(planar_session), "--method", "hybrid", "--out", str(planar_session / "hyb")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "1-D only" in err[0]


def test_error_map_exaggeration_is_stated_and_round():
    from lps_gui.report.figures.plots import nice_exaggeration

    assert nice_exaggeration(10.0, 10.0) == 500.0  # 0.8 * 10 mm / 10 um = 800 -> 500
    assert nice_exaggeration(0.0, 10.0) == 1.0


def test_planar_straightness_in_and_out_of_the_plane_carry_their_resolution(planar_session):
    r = json.loads((planar_session / "results.json").read_text())
    for axis in ("X", "Y"):
        a = r["figures"]["planar"]["per_axis"][axis]
        for key in ("straightness", "out_of_plane"):
            d = a[key]
            assert d["noise_span_um"] > 0 and isinstance(d["resolved"], bool)
    row = next(p for p in r["positions"] if p["used"])
    assert "out_of_plane_um" in row and row["out_of_plane_sigma_um"] > 0
    summary = {name: value for name, value, *_ in r["summary"]}
    # an unresolved span has its row but no value: never a finding
    for axis in ("x", "y"):
        if not r["figures"]["planar"]["per_axis"][axis.upper()]["out_of_plane"]["resolved"]:
            assert summary[f"out_of_plane_straightness_{axis}_max"] is None


def test_out_of_plane_displacement_is_compared_with_the_truth_at_the_board_plane(planar_session):
    r = json.loads((planar_session / "results.json").read_text())
    tc = r["truth_comparison"]
    assert 0.3 < tc["out_of_plane_z_mean_square"] < 3.0, tc
    assert any(p.get("truth_out_of_plane_um") is not None for p in r["positions"])
