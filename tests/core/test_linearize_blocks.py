"""The pose-only normal equations (contracted per corner, issue 15) equal the pose part of the full Jacobian's."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.models.joint_lm import LpsState, linearize
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec, simulate_views


@pytest.fixture(scope="module")
def case():
    spec = paper_rig_spec(plan=Plan(start_mm=0.0, stop_mm=149.0, step_mm=1.0))
    views = simulate_views(spec)
    corners = views.corners_px.copy()
    corners[3, 5] = np.nan
    corners[70, :40] = np.nan
    R, t = views.R_cam_board, views.t_cam_board
    n = (t[-1] - t[0]) / np.linalg.norm(t[-1] - t[0])
    rng = np.random.default_rng(1)
    state = LpsState(R[0], t[0] + rng.normal(size=3) * 0.1, n, (t - t[0]) @ n + rng.normal(size=len(t)) * 0.01, spec.rig.intrinsics)
    return state, spec.rig.board.object_points(), corners, np.isfinite(corners).all(axis=-1)


@pytest.mark.parametrize("huber_c", [None, 0.15])
def test_pose_blocks_equal_the_full_jacobian_ones(case, huber_c):
    state, X, corners, mask = case
    pose, r_pose = linearize(state, X, corners, mask, huber_c)
    full, r_full = linearize(state, X, corners, mask, huber_c, with_intrinsics=True)
    p = pose.A.shape[0]
    np.testing.assert_allclose(pose.A, full.A[:p, :p], rtol=1e-10, atol=1e-9 * np.abs(full.A).max())
    np.testing.assert_allclose(pose.B, full.B[:, :p], rtol=1e-10, atol=1e-10 * np.abs(full.B).max())
    np.testing.assert_allclose(pose.g_theta, full.g_theta[:p], rtol=1e-10, atol=1e-10 * np.abs(full.g_theta).max())
    for name in ("D", "g_s", "weights"):
        np.testing.assert_allclose(getattr(pose, name), getattr(full, name), rtol=1e-12, atol=1e-12)
    assert pose.cost == pytest.approx(full.cost, rel=1e-12) and pose.ssr == pytest.approx(full.ssr, rel=1e-12)
    np.testing.assert_array_equal(r_pose, r_full)
    if huber_c is not None:
        assert (pose.weights[mask] < 1).any()  # the loss is active


@pytest.mark.parametrize("with_intrinsics", [False, True])
def test_a_view_selection_equals_masking_the_other_views(case, with_intrinsics):
    """One pass over every view with ``views`` selecting the solve's equals the pass over the used views' corners."""
    from lps_gui.core.models.joint_lm import linearize_poses

    state, X, corners, mask = case
    used = np.ones(mask.shape[0], bool)
    used[[2, 40, 41]] = False
    sel, pn = linearize_poses(state, X, corners, mask, with_intrinsics=with_intrinsics, views=used)
    masked, _ = linearize(state, X, corners, mask & used[:, None], with_intrinsics=with_intrinsics)
    for name in ("A", "B", "D", "g_theta", "g_s", "weights", "view_ssr"):
        np.testing.assert_allclose(getattr(sel, name), getattr(masked, name), rtol=1e-12, atol=1e-12 * np.abs(getattr(masked, name)).max())
    assert (sel.ssr, sel.n_obs) == pytest.approx((masked.ssr, masked.n_obs), rel=1e-12)
    assert np.all(pn.ssr[~used] > 0)  # the views left out still have their own blocks
