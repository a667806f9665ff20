"""The session is read once on the estimate path (issue 34): every results builder is given the value read."""
from __future__ import annotations

from collections import Counter

import pytest

import lps_gui.sim.truth as sim_truth
from lps_gui.cli import main as lps_main
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.session import Session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session

READERS = ("board", "plan", "targets", "records", "intrinsics")  # each parses session.json or captures.jsonl


def _simulate(kind: str, folder) -> None:
    if kind == "line":
        simulate_point_session(small_spec(seed=2, views=12, directions="both"), folder)
    elif kind == "planar":
        assert lps_main(["simulate", "--planar", "--points", str(folder), "--preset", "small-planar", "--seed", "4"]) == 0
    else:
        assert lps_main(["simulate", "--points", str(folder), "--preset", "small-row"]) == 0


@pytest.mark.parametrize("kind", ["line", "planar", "row"])
def test_each_file_of_the_session_is_read_once_per_estimate(tmp_path, monkeypatch, kind):
    _simulate(kind, tmp_path / "s")
    calls: Counter[str] = Counter()

    def counted(name, original):
        def reader(*args, **kwargs):
            calls[name] += 1
            return original(*args, **kwargs)
        return reader

    for name in READERS:
        monkeypatch.setattr(Session, name, counted(name, getattr(Session, name)))
    monkeypatch.setattr(Session, "open", classmethod(counted("open", Session.open.__func__)))
    monkeypatch.setattr(sim_truth, "read_truth", counted("truth", sim_truth.read_truth))  # truth.jsonl
    results = estimate_session(tmp_path / "s")
    assert results["truth_comparison"] and results["uncertainty"]  # the builders that read the session ran
    assert calls["open"] == 1 and calls["records"] == 1 and calls["truth"] == 1, calls
    assert max(calls.values()) == 1, calls
