"""Issue 34: the results builders compute the verdict, the ASME B5.64 ratios and the truth self-check from the values
passed down to them, never by reading back the results document they are building: with every way of typing or
reading a document made to fail, a simulated session with a stage specification still gets all three."""
from __future__ import annotations

import json

import pytest

from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.results.model import Results
from lps_gui.io.results.verdict_rows import session_verdicts
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.pipeline.results.uncertainty import BudgetSource
from lps_gui.sim.points import simulate_point_session
from lps_gui.sim.truth_figures import CheckedValues

SPEC = {"accuracy_um": 20, "repeatability_um": 5, "straightness_um": 38}


class DocumentRead(AssertionError):
    """A builder read back the document it is building."""


def _refuse(*_args, **_kwargs):
    raise DocumentRead("a results builder read a results document")


@pytest.fixture
def no_document_reads(monkeypatch):
    """Every reader of a whole results document fails loudly while this is on."""
    monkeypatch.setattr(Results, "from_dict", classmethod(_refuse))  # as_results / read_results of a dict
    monkeypatch.setattr(CheckedValues, "of_document", classmethod(_refuse))  # the self-check's reader
    monkeypatch.setattr(BudgetSource, "of_results", classmethod(_refuse))  # the budget's reader


@pytest.fixture(scope="module")
def session_folder(tmp_path_factory):
    spec = small_spec(seed=3, views=12, directions="both", runs=2, noise_px=0.02)
    session = simulate_point_session(spec, tmp_path_factory.mktemp("no-read") / "session")
    meta = json.loads((session.folder / "session.json").read_text())
    meta["stage_spec"] = SPEC
    (session.folder / "session.json").write_text(json.dumps(meta))
    return session.folder


def test_the_guard_catches_a_builder_that_reads_the_document(no_document_reads):
    """The guard is live: the verdict rows of a document (a reader's way) are refused under it."""
    with pytest.raises(DocumentRead):
        session_verdicts({"format": "lps-results/1", "positions": [{"index": 0}]}, SPEC)


def test_verdict_asme_and_self_check_come_from_the_values_passed_down(session_folder, tmp_path, no_document_reads):
    results = estimate_session(session_folder, out_dir=tmp_path)
    assert results["verdict"]["checks"] and results["verdict"]["overall"] != "no specification"
    ratios = results["asme_b5_64"]["test_uncertainty_ratio"]
    assert [r["figure"] for r in ratios] == [c["name"] for c in results["verdict"]["checks"]]
    assert results["truth_comparison"]["self_check"] == {"passed": True, "problems": []}


def test_the_values_give_what_a_reader_of_the_finished_document_gives(session_folder, tmp_path):
    """The verdict written from the values is the one a reader computes from the finished document."""
    results = estimate_session(session_folder, out_dir=tmp_path)
    rows = session_verdicts(results, SPEC)
    assert [(c["name"], c["verdict"], c["u_k2"]) for c in results["verdict"]["checks"]] == [
        (r.name, r.verdict, pytest.approx(r.u_k2)) for r in rows]


def test_truth_comparison_returns_new_rows_and_leaves_the_builders_rows_as_they_were(session_folder):
    """Issue 34, builders return values: the truth columns come back on new rows; the rows handed in are read-only
    here (a write to them raises) and keep exactly their own columns."""
    from types import MappingProxyType

    from lps_gui.pipeline import estimate as pipeline
    from lps_gui.pipeline.session_input import read_session_input
    from lps_gui.sim.truth import truth_comparison

    inp = read_session_input(session_folder, None)
    obs = pipeline.observations_from_session(inp)
    est = pipeline.estimate_with_self_calibration(obs, pipeline.make_options("joint"))
    rows = pipeline.position_rows(obs, est)
    before = [dict(r) for r in rows]
    section, with_truth = truth_comparison(obs, est, inp.truth, [MappingProxyType(r) for r in rows])
    assert rows == before
    assert section["position_rms_error_um"] is not None
    assert all(set(n) - set(r) >= {"truth_deviation_um"} for n, r in zip(with_truth, rows))
    assert [{k: n[k] for k in r} for n, r in zip(with_truth, rows)] == before  # the estimate's columns unchanged
