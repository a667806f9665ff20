"""`lps report`: one-line error without results, a PDF with them."""
from __future__ import annotations

import json

import pytest

from lps_gui.cli import main
from tests.report.conftest import make_results


def test_report_without_results_tells_to_estimate(tmp_path, capsys):
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "session.json").write_text("{}")
    assert main(["report", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip()
    assert "lps estimate" in err and len(err.splitlines()) == 1


def test_report_on_a_folder_that_is_no_session_says_so(tmp_path, capsys):
    (tmp_path / "s").mkdir()
    assert main(["report", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip()
    assert "not a session folder" in err and "lps estimate" not in err and len(err.splitlines()) == 1


@pytest.mark.gui
def test_report_writes_the_pdf(tmp_path, capsys):
    folder = tmp_path / "s"
    folder.mkdir()
    results, _ = make_results()
    (folder / "results.json").write_text(json.dumps(results))
    assert main(["report", str(folder), "--out", str(tmp_path / "x.pdf")]) == 0
    assert (tmp_path / "x.pdf").read_bytes().startswith(b"%PDF")
    assert str(tmp_path / "x.pdf") in capsys.readouterr().out
