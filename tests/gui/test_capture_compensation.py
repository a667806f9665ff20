"""The capture panel's compensation field: the engine commands through the table, captures.jsonl records it."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.core.metrology.compensation import CompensationTable
from lps_gui.io.compensation_file import write_table
from tests.gui.test_capture_flow import SMALL_PLAN, capture_window

pytestmark = pytest.mark.gui


def test_capture_panel_compensation_field(qtbot, make_window, tmp_path):
    x = np.linspace(-5.0, 15.0, 5)
    table = CompensationTable(x, x + 0.004, x + 0.002, np.zeros(5), np.zeros(5), True)
    path = write_table(tmp_path / "t.csv", table, "csv")
    window, cap = capture_window(qtbot, make_window, SMALL_PLAN, tmp_path / "run")
    cap.compensation.set_text(str(path))
    with qtbot.waitSignal(cap.session_done, timeout=60000):
        cap.start_btn.click()
    recs = [json.loads(line) for line in (tmp_path / "run" / "captures.jsonl").read_text().splitlines()]
    assert [r["commanded_mm"] for r in recs] == pytest.approx([r["target_mm"] - 0.004 for r in recs], abs=1e-6)
    assert json.loads((tmp_path / "run" / "session.json").read_text())["compensation"]["file"] == str(path)
