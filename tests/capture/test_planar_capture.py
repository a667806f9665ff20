"""A 2-D capture through the engine: on the simulated gantry, through the GRBL emulator, and
interrupted then resumed on a rebuilt rig (equal to an uninterrupted run, byte for byte)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.core.clock import SimClock
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import small_planar_spec
from lps_gui.io.session import Session
from lps_gui.pipeline.detect import detect_session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.session import create_simulated_session, reopen_simulated_rig, simulated_engine
from tests.capture.helpers import capture_through_emulator

PLAN = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(40.0, 20.0), step_mm=(10.0, 10.0), directions="both",
               settle_s=0.1, overshoot_mm=1.0, feed_mm_min=3000.0)


def spec():
    return small_planar_spec(seed=7, plan=PLAN)


def capture(folder, stop_after: int | None = None):
    session, stage, camera = create_simulated_session(folder, spec(), clock=SimClock())
    stage.connect()
    engine = simulated_engine(session, stage, camera)
    if stop_after is not None:
        engine.subscribe(lambda e: engine.abort() if e.kind == "frame" and e.index + 1 >= stop_after else None)
    summary = engine.run()
    stage.disconnect()
    return Session.open(folder), summary


def images(session: Session) -> dict[str, bytes]:
    return {r.file: (session.folder / r.file).read_bytes() for r in session.records()}


def records(session: Session) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "time"}
            for line in session.captures_path.read_text().splitlines()]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return capture(tmp_path_factory.mktemp("planar") / "ref")


def test_planar_capture_lists_xy_targets_and_reports_both_axes(reference):
    session, summary = reference
    assert summary.state == "done" and summary.listed == PLAN.n_frames() == 30
    recs = session.records()
    assert recs[0].target_mm == (0.0, 0.0) and recs[6].target_mm == (30.0, 10.0)  # serpentine row 2
    for r in recs:
        assert np.allclose(r.reported_mm, r.target_mm, atol=1e-6)
    truth = session.truth
    assert len(truth["plane_mm"]) == 30 and len(truth["board_plane_mm"]) == 30


def test_engine_approaches_each_axis_from_its_planned_side(reference):
    session, _ = reference
    # the true carriage position carries the backlash of each axis' approach side
    stops = {s.index: s for s in session.plan().stops()}
    truth = session.truth
    errors = small_planar_spec().rig.errors
    for i, p in zip(truth["index"], truth["plane_mm"]):
        s = stops[i]
        expected = errors.true_pose(np.array([s.target_mm]), np.array([s.approach], float)).plane_mm[0]
        assert np.allclose(p, expected, atol=5e-3)  # within repeatability (0.5 um) and the moves' ends


def test_interrupted_and_resumed_on_a_rebuilt_rig_equals_uninterrupted(tmp_path, reference):
    folder = tmp_path / "cut"
    cut, summary = capture(folder, stop_after=13)
    assert summary.state == "aborted" and 13 <= summary.listed < 30
    stage, camera = reopen_simulated_rig(cut, clock=SimClock())  # as after a crash: a new process
    stage.connect()
    done = simulated_engine(cut, stage, camera).run()
    stage.disconnect()
    assert done.state == "done"
    resumed = Session.open(folder)
    ref = reference[0]
    assert records(resumed) == records(ref)
    assert images(resumed) == images(ref)
    assert resumed.truth["plane_mm"] == ref.truth["plane_mm"]


def test_detect_and_estimate_the_captured_planar_session(reference):
    session, _ = reference
    detect_session(session.folder, workers=1)
    results = estimate_session(session.folder)
    assert results["axes"] == ["X", "Y"]
    tc = results["truth_comparison"]
    assert tc["position_rms_error_um"] is not None
    # the error against truth is of the size of the reported sigma
    assert max(tc["per_coordinate_rms_error_um"]) < 3.0 * tc["mean_sigma_um"], tc


def test_planar_capture_through_the_grbl_emulator(tmp_path):
    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(10.0, 10.0), step_mm=(10.0, 10.0), settle_s=0.05,
                   overshoot_mm=1.0, feed_mm_min=6000.0)
    capture_through_emulator(tmp_path / "grbl", small_planar_spec(seed=2, plan=plan), time_scale=20.0)
    recs = Session.open(tmp_path / "grbl").records()
    assert [r.target_mm for r in recs] == [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
    for r in recs:
        assert np.allclose(r.reported_mm, r.target_mm, atol=1e-3)
