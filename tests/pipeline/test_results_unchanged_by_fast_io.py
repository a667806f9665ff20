"""Results of `lps estimate` are the same to the printed digits with the numpy corners.vnl reader as with
the line-by-line one it replaced (issue 15): positions.csv and summary.csv byte for byte, results.json
numbers exactly (timings and dates aside).

The session is simulated through the CLI (with missing corners), so the test follows whatever simulator
the project has; the reference reader is kept in tests/io/corners_vnl_reference.py.
"""
from __future__ import annotations

import json

import pytest

import lps_gui.pipeline.estimate as pipeline_estimate
from lps_gui.cli import main
from tests.io import corners_vnl_reference as ref

VOLATILE = {"timings_s", "created"}


def _numbers(doc):
    """results.json without what changes from run to run."""
    if isinstance(doc, dict):
        return {k: _numbers(v) for k, v in doc.items() if k not in VOLATILE}
    if isinstance(doc, list):
        return [_numbers(v) for v in doc]
    return doc


@pytest.mark.parametrize("preset,extra", [("small", ["--missing-fraction", "0.02"]), ("paper-rig", ["--stops", "40"])])
def test_estimate_results_identical_with_the_previous_reader(tmp_path, monkeypatch, capsys, preset, extra):
    session = tmp_path / "session"
    assert main(["simulate", "--points", "--preset", preset, *extra, str(session)]) == 0
    capsys.readouterr()
    assert main(["estimate", str(session), "--out", str(tmp_path / "new")]) == 0
    new_summary = capsys.readouterr().out
    monkeypatch.setattr(pipeline_estimate, "read_corners_vnl", ref.read_corners_vnl)
    assert main(["estimate", str(session), "--out", str(tmp_path / "old")]) == 0
    old_summary = capsys.readouterr().out
    for name in ("positions.csv", "summary.csv"):
        assert (tmp_path / "new" / name).read_bytes() == (tmp_path / "old" / name).read_bytes(), name
    new = json.loads((tmp_path / "new" / "results.json").read_text())
    old = json.loads((tmp_path / "old" / "results.json").read_text())
    assert _numbers(new) == _numbers(old)
    # the printed summary differs only in the solver's time
    assert [line.split(", ")[:-1] for line in new_summary.splitlines()[:1]] == [line.split(", ")[:-1] for line in old_summary.splitlines()[:1]]
    assert new_summary.splitlines()[1:] == old_summary.splitlines()[1:]
