"""`lps capture --segment-stops`: one board moved between segments, the operator answering at each pause."""
from __future__ import annotations

import io
import json

from lps_gui.cli import main as lps_main
PLAN = ["--start", "0", "--stop", "16", "--step", "2", "--settle", "0", "--segment-stops", "5", "--overlap-stops", "2"]


def _segments(folder):
    return [json.loads(line)["segment"] for line in (folder / "captures.jsonl").read_text().splitlines()]


def test_the_operator_moves_the_board_between_segments(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO("\n\n"))
    rc = lps_main(["capture", "--out", str(tmp_path / "s"), *PLAN])
    err = capsys.readouterr().err
    assert rc == 0 and _segments(tmp_path / "s") == [0] * 5 + [1] * 5 + [2] * 3
    assert "segment 2 of 3: move the board 6 mm along +X" in err and "segment 3 of 3" in err
    plan = json.loads((tmp_path / "s" / "session.json").read_text())["plan"]
    assert plan["segments"] == [[0.0, 8.0], [6.0, 14.0], [12.0, 16.0]]


def test_without_anyone_to_answer_the_capture_stops_at_the_pause_and_resumes(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert lps_main(["capture", "--out", str(tmp_path / "s"), *PLAN]) == 3
    assert "nobody to move the board" in capsys.readouterr().err and _segments(tmp_path / "s") == [0] * 5
    monkeypatch.setattr("sys.stdin", io.StringIO("\n\n"))
    assert lps_main(["capture", "--resume", str(tmp_path / "s")]) == 0
    assert _segments(tmp_path / "s") == [0] * 5 + [1] * 5 + [2] * 3
