"""As-found / as-left report from two estimated sessions."""
from __future__ import annotations

from dataclasses import replace

import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.errors import InputError
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pdf.compare import (
    comparison_figure,
    comparison_rows,
    improvement_factor,
    true_E_um,
    write_comparison,
)
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    root = tmp_path_factory.mktemp("cmp")
    plan = Plan(start_mm=0.0, stop_mm=30.0, step_mm=1.5, directions="both", runs=1)
    out = []
    for name, errors in (("before", StageErrorModel(scale_ppm=80, periodic_um=6, backlash_um=12)),
                         ("after", StageErrorModel(periodic_um=0.5, backlash_um=1))):
        spec = replace(paper_rig_spec(seed=1, errors=errors, plan=plan), noise_px=0.023)
        simulate_point_session(spec, root / name)
        out.append((root / name, estimate_session(root / name)))
    return out


def test_rows_figure_and_pdf(pair, tmp_path):
    (bdir, before), (adir, after) = pair
    rows = comparison_rows(before, after)
    assert rows[0][0] == "ISO 230-2 Systematic deviation E (bidirectional)"  # the main report's name
    ratio, u_ratio = rows[0][3].split(" \u00b1 ")
    assert float(ratio.rstrip("x")) == pytest.approx(improvement_factor(before, after), rel=0.06)
    assert float(u_ratio) > 0  # the improvement carries its U
    assert all(" \u00b1 " in c for r in rows for c in r[1:3] if c != "\u2014")  # U on every figure
    assert improvement_factor(before, after) > 5 and true_E_um(before) > 5 * true_E_um(after)
    fig = comparison_figure(before, after)
    assert {s.label for s in fig.series} == {"as found forward \u2191", "as found backward \u2193",
                                            "as left forward \u2191", "as left backward \u2193"}
    path = write_comparison(bdir, adir, tmp_path / "c.pdf")
    assert path.read_bytes().startswith(b"%PDF")
    with pytest.raises(InputError, match="folder not found"):
        write_comparison(bdir, adir, tmp_path / "nope" / "c.pdf")


def test_compare_names_u_verdicts_and_labels_true_against_measured(tmp_path):
    import json

    from tests.report.conftest import make_results
    from tests.report.test_layout_fit import SPEC, _session

    before, truth_b = make_results(seed=3)
    after, truth_a = make_results(seed=4)
    bdir = _session(tmp_path / "b", before, truth_b, SPEC)
    adir = _session(tmp_path / "a", after, truth_a, SPEC)
    from lps_gui.report.pdf.compare import compare_rows, verdict_rows

    rows = {r.name: r for r in compare_rows(before, after)}
    e = rows["ISO 230-2 Systematic deviation E (bidirectional)"]
    assert e.u_before == before["uncertainty"]["figures_k2"]["E_um"] and e.u_after == after["uncertainty"]["figures_k2"]["E_um"]
    assert e.u_ratio == pytest.approx(e.ratio * ((e.u_before / e.before) ** 2 + (e.u_after / e.after) ** 2) ** 0.5)
    verdict = verdict_rows(before, after, SPEC, SPEC)
    assert [r[0] for r in verdict] == ["Positional accuracy", "Repeatability", "Straight-line accuracy"]
    assert verdict[0][1].startswith("A/2 = ") and " \u00b1 " in verdict[0][1] and verdict[0][2].startswith("A/2 = ")
    clipped: list[str] = []
    path = write_comparison(bdir, adir, tmp_path / "c.pdf", clipped)
    assert clipped == [] and path.exists()
    assert json.loads((bdir / "results.json").read_text())["figures"]  # inputs untouched


def test_compare_reads_the_noise_corrected_E_results_json_holds(pair):
    """One definition: the measured E of the comparison (and the demo's compensation pass) is results.json's, with
    the camera's noise taken out, never a recomputation from the deviations (which would keep the noise)."""
    import copy

    from lps_gui.report.pdf.compare import session_E_um

    (_, before), _ = pair
    iso = before["figures"]["iso230_2"]
    assert iso["noise_correction"]["E_um"]["measured"] != iso["E_um"]  # the correction moved it
    assert session_E_um(before) == pytest.approx(iso["E_um"])
    moved = copy.deepcopy(before)
    moved["figures"]["iso230_2"]["E_um"] = iso["E_um"] + 3.0
    assert session_E_um(moved) == pytest.approx(iso["E_um"] + 3.0)
    assert true_E_um(moved) == pytest.approx(true_E_um(before))  # the truth's E is the truth column's own
