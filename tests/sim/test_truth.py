"""truth.jsonl: pruned to listed captures (once each) before a capture resumes; folded into session.json."""
from __future__ import annotations

import json

from lps_gui.sim.truth import TRUTH_FILE, append_truth, finalize_truth, prune_truth, read_truth
from lps_gui.core.plan import Plan
from lps_gui.io.session import CaptureRecord, Session
from tests.capture.helpers import tiny_spec


def test_prune_drops_unlisted_duplicate_and_torn_lines(tmp_path):
    spec = tiny_spec(Plan(start_mm=0.0, stop_mm=4.0, step_mm=1.0))
    session = Session.create(tmp_path / "s", spec.rig.board, spec.plan, truth={"simulated": True})
    for i in range(2):
        session.append(CaptureRecord(i, 1, "+", float(i), float(i), f"images/{i:06d}.png", "x", 0.0))
    for i, axis in ((0, 0.001), (1, 1.002), (1, 1.002), (2, 2.0)):  # 1 twice, 2 never listed
        append_truth(session, i, {"axis_mm": axis, "straightness_um": [0, 0], "angles_urad": [0, 0, 0]})
    with open(session.folder / TRUTH_FILE, "a") as f:
        f.write('{"index": 3, "axis')  # torn by a kill
    prune_truth(session)
    lines = [json.loads(line) for line in (session.folder / TRUTH_FILE).read_text().splitlines()]
    assert [d["index"] for d in lines] == [0, 1]
    finalize_truth(session)
    truth = Session.open(session.folder).truth
    assert truth["simulated"] and truth["index"] == [0, 1]
    assert truth["axis_mm"] == [0.001, 1.002]
    assert truth["positions_mm"] == [0.0, 1.002 - 0.001]
    assert set(read_truth(session)) == {0, 1}
