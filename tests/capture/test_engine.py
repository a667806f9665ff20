"""The capture engine on the simulated rig, validated against the simulated stage's truth."""
from __future__ import annotations

import errno
import shutil
import threading
from collections import namedtuple

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.errors import InputError
from lps_gui.io.session import Session
from lps_gui.sim.truth import read_truth
from tests.capture.helpers import (
    PLAN20,
    assert_listed_frames_intact,
    image_bytes,
    records_without_time,
    start_capture,
)


def test_bidirectional_two_runs_of_20_targets(reference_capture):
    session, summary, stage = reference_capture
    assert summary.state == "done" and summary.captured == summary.listed == summary.total == 80
    assert summary.elapsed_s < 30.0  # simulated time: moves, settles and grabs
    records = session.records()
    expected = list(PLAN20.stops())
    assert [(r.index, r.run, r.direction, r.target_mm) for r in records] == [
        (s.index, s.run, s.direction, s.target_mm) for s in expected
    ]
    assert_listed_frames_intact(session)
    np.testing.assert_allclose([r.reported_mm for r in records], [s.target_mm for s in expected], atol=1e-9)
    # truth: true position = target + systematic error (backlash of the run's direction) + repeatability
    truth = Session.open(session.folder).truth
    assert truth["index"] == list(range(80))
    errors = stage.errors
    target = np.array([r.target_mm for r in records])
    sign = np.array([1.0 if r.direction == "+" else -1.0 for r in records])
    resid_um = (np.array(truth["axis_mm"]) - target) * 1e3 - errors.positioning_error_um(target, sign)
    assert np.abs(resid_um).max() < 5.0 * errors.repeatability_um
    assert abs(np.std(resid_um) - errors.repeatability_um) < 0.4 * errors.repeatability_um
    np.testing.assert_allclose(truth["positions_mm"], np.array(truth["axis_mm"]) - truth["axis_mm"][0])


def test_each_target_is_approached_from_its_own_direction(tmp_path):
    """With backlash only, the true position reveals the approach side of every frame, even after a pause."""
    errors = StageErrorModel(backlash_um=50.0)
    plan = Plan(start_mm=0.0, stop_mm=6.0, step_mm=2.0, directions="both", runs=2, overshoot_mm=1.0, settle_s=0.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    stage.errors = errors
    stops = {"n": 0}

    def stop_after_five(event):
        if event.kind == "frame":
            stops["n"] += 1
            if stops["n"] == 5:
                engine.abort()

    engine.subscribe(stop_after_five)
    assert engine.run().state == "aborted"
    stage.move_to(3.0, 600.0)  # the operator moves the stage meanwhile
    stage.wait_idle()
    assert engine.run().state == "done"
    truth = read_truth(session)
    for r in session.records():
        sign = 1.0 if r.direction == "+" else -1.0
        assert truth[r.index]["axis_mm"] == pytest.approx(r.target_mm - sign * 0.025, abs=1e-9), r


def test_vanished_port_pauses_with_a_clear_error_and_resumes(tmp_path, reference_capture):
    session, stage, camera, engine = start_capture(tmp_path / "s")
    stage.disconnect_fault(at_time_s=12.0)  # mid-run, simulated time
    first = engine.run()
    assert first.state == "paused" and engine.state == "paused"
    assert "vanished" in first.error and "reconnect" in first.error
    assert 0 < first.listed < 80
    assert_listed_frames_intact(session)
    with pytest.raises(Exception):
        stage.status()
    stage.connect()  # the reconnect
    second = engine.run()
    assert second.state == "done" and second.listed == 80 and second.captured == 80 - first.listed
    assert_listed_frames_intact(session)
    ref = reference_capture[0]
    assert records_without_time(session) == records_without_time(ref)
    assert image_bytes(session) == image_bytes(ref)
    assert Session.open(session.folder).truth["axis_mm"] == Session.open(ref.folder).truth["axis_mm"]


def test_unwritable_folder_fails_before_the_first_move(tmp_path):
    session, stage, camera, engine = start_capture(tmp_path / "s")
    images = session.folder / "images"
    shutil.rmtree(images)
    images.write_bytes(b"not a folder")  # works even as root, unlike a chmod
    with pytest.raises(InputError, match="cannot write here"):
        engine.run()
    assert stage.clock.now() == 0.0 and stage.position_mm() == 0.0
    assert session.records() == []


def test_full_disk_fails_before_the_first_move(tmp_path, monkeypatch):
    session, stage, camera, engine = start_capture(tmp_path / "s")
    Usage = namedtuple("Usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: Usage(10**9, 10**9 - 10**6, 10**6))
    with pytest.raises(InputError, match="MB free"):
        engine.run()
    assert stage.clock.now() == 0.0 and session.records() == []


def test_plan_outside_the_travel_fails_before_the_first_move(tmp_path):
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0))
    stage.travel_mm = (0.0, 100.0)  # the first overshoot (-1 mm) is beyond the low limit
    with pytest.raises(InputError, match="stage travels 0..100 mm"):
        engine.run()
    assert stage.clock.now() == 0.0 and session.records() == []


def test_disk_failure_mid_run_pauses_and_keeps_everything(tmp_path):
    plan = Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, settle_s=0.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    real_write = session.write_image
    calls = {"n": 0}

    def failing_write(name, data):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(name, data)

    session.write_image = failing_write
    first = engine.run()
    assert first.state == "paused" and "No space left" in first.error and first.listed == 2
    assert engine.run().state == "done"
    assert [r.index for r in session.records()] == list(range(5))
    assert_listed_frames_intact(session)


def test_pause_resume_from_another_thread(tmp_path):
    plan = Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, settle_s=0.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    paused = threading.Event()

    def on_event(event):
        if event.kind == "frame" and event.index == 1:
            engine.pause()
        if event.kind == "paused":
            paused.set()

    engine.subscribe(on_event)
    result = {}
    worker = threading.Thread(target=lambda: result.setdefault("summary", engine.run()))
    worker.start()
    assert paused.wait(timeout=30)
    snap = engine.progress()
    assert snap.state == "paused" and snap.done == 2 and snap.total == 5
    with pytest.raises(InputError, match="already running"):
        engine.run()
    engine.resume()
    worker.join(timeout=30)
    assert result["summary"].state == "done"
    snap = engine.progress()
    assert (snap.state, snap.done, snap.eta_s) == ("done", 5, 0.0)


def test_abort_mid_stop_and_resume_gives_the_uninterrupted_session(tmp_path):
    plan = Plan(start_mm=0.0, stop_mm=6.0, step_mm=2.0, frames_per_stop=3, settle_s=0.0)
    ref, *_, ref_engine = start_capture(tmp_path / "ref", plan=plan)
    assert ref_engine.run().state == "done"
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    engine.subscribe(lambda e: engine.abort() if e.kind == "frame" and e.index == 4 else None)
    assert engine.run().state == "aborted"
    assert [r.index for r in session.records()] == [0, 1, 2, 3, 4]  # frame 2 of stop 1 still missing
    assert engine.run().state == "done"
    assert records_without_time(session) == records_without_time(ref)
    assert image_bytes(session) == image_bytes(ref)
    truth = read_truth(session)
    assert truth[3]["axis_mm"] == truth[4]["axis_mm"] == truth[5]["axis_mm"]  # one pose per stop


def test_cancel_token_stops_and_progress_callback_counts(tmp_path):
    from lps_gui.core.progress import CancelToken

    plan = Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, settle_s=0.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    token = CancelToken()
    seen = []

    def progress(done, total, message=""):
        seen.append((done, total))
        if done == 3:
            token.cancel()

    summary = engine.run(progress=progress, cancel=token)
    assert summary.state == "aborted" and summary.listed == 3
    assert seen[0] == (0, 5) and seen[-1] == (3, 5)


def test_a_repeated_target_is_approached_again_from_its_own_side(tmp_path):
    plan = Plan(targets_mm=(0.0, 2.0, 2.0, 4.0), frames_per_stop=2, settle_s=0.0)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan=plan)
    kinds = []
    engine.subscribe(lambda e: kinds.append((e.kind, e.index)) if e.kind in ("approach", "move") else None)
    assert engine.run().state == "done"
    assert kinds == [("approach", 0), ("move", 0), ("move", 2), ("approach", 4), ("move", 4), ("move", 6)]


def test_frames_record_their_time_after_the_move(tmp_path):
    """captures.jsonl since_move_s: the engine's clock from the stage reporting the move done (settling tests)."""
    from lps_gui.core.planning.plan import Plan
    from tests.capture.helpers import start_capture

    plan = Plan(start_mm=0.0, stop_mm=2.0, step_mm=2.0, directions="+", settle_s=0.05, frames_per_stop=3)
    session, stage, camera, engine = start_capture(tmp_path / "s", plan, exposure_s=0.02)
    assert engine.run().state == "done"
    since = [r.since_move_s for r in session.records()]
    assert since == pytest.approx([0.07, 0.09, 0.11] * 2)  # settle, then one exposure per frame
