"""The block runner: same results as a loop, in order, and no deadlock when a block runs blocks."""
from __future__ import annotations

import numpy as np

from lps_gui.core.numerics import blocks


def test_results_come_back_in_order_and_equal_a_loop(monkeypatch):
    monkeypatch.setenv("LPS_THREADS", "2")
    items = list(range(23))
    assert blocks.in_parallel(lambda i: i * i, items) == [i * i for i in items]


def test_a_block_that_runs_blocks_does_not_wait_on_itself(monkeypatch):
    monkeypatch.setenv("LPS_THREADS", "2")
    out = blocks.in_parallel(lambda i: sum(blocks.in_parallel(lambda j: i * j, range(5))), range(6))
    assert out == [10 * i for i in range(6)]


def test_one_thread_is_a_plain_loop(monkeypatch):
    monkeypatch.setenv("LPS_THREADS", "1")
    assert blocks.worker_count() == 1
    seen = []
    blocks.in_parallel(seen.append, [3, 1, 2])
    assert seen == [3, 1, 2]


def test_pose_blocks_do_not_depend_on_the_thread_count(monkeypatch):
    """Threads only change where blocks run: every number is the same bit for bit."""
    from lps_gui.core.numerics.pose_normals import BLOCK_VIEWS, pose_normals
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.truth.simulate import paper_rig_spec, simulate_views

    spec = paper_rig_spec(plan=Plan(start_mm=0.0, stop_mm=float(3 * BLOCK_VIEWS), step_mm=1.0))
    views = simulate_views(spec)
    mask = np.isfinite(views.corners_px).all(axis=-1)
    args = (views.R_cam_board, views.t_cam_board, spec.rig.board.object_points(), views.corners_px, mask,
            spec.rig.intrinsics)
    runs = []
    for n in ("1", "2"):
        monkeypatch.setenv("LPS_THREADS", n)
        runs.append(pose_normals(*args, with_intrinsics=True))
    for name in ("H", "g", "ssr", "H_pose_intrinsics", "H_intrinsics", "g_intrinsics"):
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name))
