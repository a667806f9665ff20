"""A stitched session rendered (one board moved between segments, SPEC 13), detected, estimated against its truth."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.planning.target_presets import small_stitched_spec
from lps_gui.core.truth.simulate import project_scene, simulate_views, true_views
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.pipeline.detect import detect_session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.images import simulate_image_session


def test_a_rendered_stitched_session_shows_each_placement_and_is_estimated_within_its_sigma(tmp_path):
    spec = small_stitched_spec(seed=1)
    session = simulate_image_session(spec, tmp_path / "s", workers=1)
    assert session.meta.get("targets") is None and session.board().n_corners == 35  # one board, as capture writes
    assert session.meta["plan"]["segments"] == [[0.0, 100.0], [60.0, 160.0], [120.0, 220.0]]
    assert session.meta["stage_spec"] == {"repeatability_um": 4.0}  # R = 4 sigma of the simulated stage
    records = session.records()
    assert [r.segment for r in records] == [0] * 6 + [1] * 6 + [2] * 6
    assert [t["id"] for t in session.truth["targets"]] == ["S0", "S1", "S2"]

    detect_session(session.folder, workers=1)
    found = read_corners_vnl(session.corners_path, 35).corners_px
    stops, R, t, _ = true_views(spec, np.random.default_rng(spec.seed))
    placed = project_scene(spec, R, t, stops)  # each view's board where it lay during the view's segment
    err = np.linalg.norm(found - placed, axis=2)
    assert np.isfinite(found[..., 0]).sum() >= 0.9 * found[..., 0].size and np.nanmax(err) < 0.5
    assert np.allclose(simulate_views(spec).corners_px, placed, atol=1.0)  # the point simulator sees the same

    results = estimate_session(session.folder)
    assert [(r["id"], r["stitch_ties"]) for r in results["targets"]] == [("S0", 0), ("S1", 3), ("S2", 3)]
    tc = results["truth_comparison"]
    assert 0.3 < tc["z_mean_square"] < 2.5, tc["z_mean_square"]  # per stop, tied visits included
    assert tc["targets"]["max_abs_z"] < 4.0
    budget = {b["source"]: b for b in results["uncertainty"]["budget"]}
    assert budget["stage repeatability at the segment ties"]["value"] == pytest.approx(1.0)


def test_a_row_of_distinct_targets_on_a_segmented_plan_stays_a_row():
    """Only one board's placements (same board, same markers, one per segment) are rendered one at a time."""
    from dataclasses import replace

    from lps_gui.core.planning.segments import stitched_segments
    from lps_gui.core.planning.target_presets import small_row_spec

    row = small_row_spec()
    segmented = replace(row, plan=replace(row.plan, segments=stitched_segments(row.plan.targets(), 8, 3)))
    assert len(segmented.plan.segments) == 3 and not segmented.stitched and small_stitched_spec().stitched
