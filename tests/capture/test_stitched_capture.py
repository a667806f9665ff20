"""A stitched plan (one board moved between segments, SPEC 13): the capture pauses to move it and records the segment."""
from __future__ import annotations

import json
import threading

import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.segments import check_segments, stitched_segments
from lps_gui.errors import InputError
from tests.capture.helpers import start_capture

PLAN = Plan(start_mm=0.0, stop_mm=16.0, step_mm=2.0, settle_s=0.0)


def stitched(plan: Plan = PLAN, segment_stops: int = 5, overlap: int = 2) -> Plan:
    return Plan(**{**plan.to_dict(), "segments": stitched_segments(plan.targets(), segment_stops, overlap)})


def run_resuming_at_each_segment(engine, moves: list[str]):
    """Run in a thread; resume each pause the plan asks for (the operator moved the board)."""
    def on_event(event):
        if event.kind == "move board":
            moves.append(event.message)
        if event.kind == "paused":
            threading.Timer(0.05, engine.resume).start()

    engine.subscribe(on_event)
    result = {}
    worker = threading.Thread(target=lambda: result.setdefault("summary", engine.run()))
    worker.start()
    worker.join(timeout=60)
    return result["summary"]


def test_segments_overlap_and_the_plan_round_trips():
    plan = stitched()
    assert plan.segments == ((0.0, 8.0), (6.0, 14.0), (12.0, 16.0))
    stops = list(plan.stops())
    assert [s.target_mm for s in stops] == [0, 2, 4, 6, 8, 6, 8, 10, 12, 14, 12, 14, 16]
    assert [s.segment for s in stops] == [0] * 5 + [1] * 5 + [2] * 3 and plan.n_frames() == 13
    assert Plan.from_dict(json.loads(json.dumps(plan.to_dict()))) == plan
    assert "segments" not in PLAN.to_dict() and all(s.segment is None for s in PLAN.stops())


def test_segments_that_share_no_stop_are_a_one_line_error():
    with pytest.raises(InputError, match="share no target"):
        check_segments([[0, 6], [8, 16]], PLAN.targets())
    with pytest.raises(InputError, match="in no segment"):
        check_segments([[0, 8], [8, 14]], PLAN.targets())


def test_the_capture_pauses_before_each_segment_and_lists_its_segment(tmp_path):
    session, _, _, engine = start_capture(tmp_path / "s", plan=stitched())
    moves: list[str] = []
    summary = run_resuming_at_each_segment(engine, moves)
    assert summary.state == "done" and summary.listed == 13
    assert len(moves) == 2 and moves[0].startswith("segment 2 of 3: move the board 6 mm along +X")
    lines = [json.loads(line) for line in (session.folder / "captures.jsonl").read_text().splitlines()]
    assert [d["segment"] for d in lines] == [0] * 5 + [1] * 5 + [2] * 3
    assert [r.segment for r in session.records()] == [d["segment"] for d in lines]


def test_a_resumed_capture_asks_again_only_when_a_new_segment_starts(tmp_path):
    session, _, _, engine = start_capture(tmp_path / "s", plan=stitched())
    stop = engine.subscribe(lambda e: engine.abort() if e.kind == "move board" else None)
    assert engine.run().state == "aborted" and len(session.records()) == 5  # stopped at the first move
    stop()
    moves: list[str] = []
    summary = run_resuming_at_each_segment(engine, moves)
    assert summary.state == "done" and len(moves) == 2  # segment 2 is asked for again, then segment 3
