"""core/joint_lm: the analytic normal equations against central finite differences; the Schur step against a dense solve."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.joint_lm import (
    N_POSE_PARAMS,
    LpsState,
    apply_step,
    huber_weights,
    linearize,
    residuals,
    robust_cost,
    solve_arrowhead,
)
from lps_gui.core.simulate import simulate_views, small_spec
from tests.core.finite_differences import central_jacobian, normalized_difference

TOL = 1e-5  # a Jacobian column scaled by 1.01 moves the normal matrix by ~1e-2 in these units


@pytest.fixture(scope="module")
def case():
    """A small rig, the state near (not at) the truth, noisy corners with a few missing: residuals are not zero."""
    spec = small_spec(seed=4, views=8, noise_px=0.3)
    views = simulate_views(spec)
    rig = spec.rig
    rng = np.random.default_rng(1)
    s = np.asarray(views.truth["positions_mm"]) + rng.normal(0, 0.01, len(views.stops))
    state = LpsState(rig.R_cam_board, views.t_cam_board[0] + 0.05, -rig.R_cam_board @ rig.u_board, s, rig.intrinsics)
    corners = views.corners_px.copy()
    corners[2, :5] = np.nan  # a few corners not found
    mask = np.all(np.isfinite(corners), axis=-1)
    return state, rig.board.object_points(), corners, mask


def numeric_jacobian(state, X, corners, mask, p):
    """d r / d (theta, s) through the solver's own update rule (apply_step), shape (K*N*2, p + K)."""
    basis = linearize(state, X, corners, mask)[0].basis
    K = state.s.size

    def r_of(step):
        return residuals(apply_step(state, step[:p], step[p:], basis), X, corners, mask).reshape(-1)

    h = np.r_[np.full(3, 1e-6), np.full(3, 1e-4), np.full(2, 1e-6), np.full(p - N_POSE_PARAMS, 1e-6), np.full(K, 1e-4)]
    if p > N_POSE_PARAMS:
        h[8:12] = 1e-3  # fx, fy, cx, cy in px
    return central_jacobian(r_of, p + K, h)


@pytest.mark.parametrize("with_intrinsics", [False, True])
def test_linearize_matches_central_differences(case, with_intrinsics):
    state, X, corners, mask = case
    eq, r = linearize(state, X, corners, mask, with_intrinsics=with_intrinsics)
    p = eq.A.shape[0]
    J = numeric_jacobian(state, X, corners, mask, p)
    Jt, Js = J[:, :p], J[:, p:]
    K = state.s.size
    H_num = J.T @ J
    H = np.zeros_like(H_num)
    H[:p, :p] = eq.A
    H[p:, :p] = eq.B
    H[:p, p:] = eq.B.T
    H[p:, p:] = np.diag(eq.D)
    assert normalized_difference(H, H_num) < TOL
    # the s-block really is diagonal (each view sees only its own position)
    assert np.allclose(H_num[p:, p:] - np.diag(np.diag(H_num[p:, p:])), 0.0, atol=1e-6 * np.max(np.diag(H_num)))
    g_num = J.T @ r.reshape(-1)
    scale = np.sqrt(np.diag(H_num)) * np.linalg.norm(r)
    assert np.max(np.abs(np.r_[eq.g_theta, eq.g_s] - g_num) / scale) < TOL
    assert eq.ssr == pytest.approx(float(np.sum(r[mask] ** 2)))
    assert eq.n_obs == 2 * mask.sum() and Jt.shape[1] == p and Js.shape[1] == K


@pytest.mark.parametrize("with_intrinsics", [False, True])
def test_a_perturbed_jacobian_term_fails_the_check(case, monkeypatch, with_intrinsics):
    """The check above can fail: scale d u / d z by 1.01 (a wrong chain-rule term) and it does."""
    import importlib

    # every block comes from core.pose_normals
    module = importlib.import_module("lps_gui.core.pose_normals")
    state, X, corners, mask = case
    real = module.project_parts

    def skewed(x, y, z, intrinsics, want_jacobian=False):
        parts = real(x, y, z, intrinsics, want_jacobian)
        if want_jacobian:  # scale d u / d z only: one term of every column that moves z
            parts = parts._replace(du=(parts.du[0], parts.du[1], 1.01 * parts.du[2]))
        return parts

    monkeypatch.setattr(module, "project_parts", skewed)
    eq, _ = linearize(state, X, corners, mask, with_intrinsics=with_intrinsics)
    monkeypatch.setattr(module, "project_parts", real)
    J = numeric_jacobian(state, X, corners, mask, eq.A.shape[0])
    H = np.block([[eq.A, eq.B.T], [eq.B, np.diag(eq.D)]])
    assert normalized_difference(H, J.T @ J) > 100 * TOL


def test_huber_weights_enter_the_normal_equations(case):
    state, X, corners, mask = case
    c = 0.2  # px: many residuals beyond it
    eq, r = linearize(state, X, corners, mask, huber_c=c)
    w = huber_weights(r, mask, c)
    e = np.linalg.norm(r, axis=-1)
    assert np.allclose(w[mask & (e <= c)], 1.0) and np.allclose(w[mask & (e > c)], c / e[mask & (e > c)])
    assert np.all(w[~mask] == 0.0)
    J = numeric_jacobian(state, X, corners, mask, eq.A.shape[0])
    sw = np.sqrt(np.repeat(w.reshape(-1), 2))
    H_num = (J * sw[:, None] ** 2).T @ J
    H = np.block([[eq.A, eq.B.T], [eq.B, np.diag(eq.D)]])
    assert normalized_difference(H, H_num) < TOL
    # Huber cost: quadratic inside c, linear outside, continuous at c
    assert robust_cost(r, mask, None) == pytest.approx(eq.ssr)
    assert robust_cost(r, mask, c) < eq.ssr


def test_schur_step_equals_the_dense_solve(case):
    state, X, corners, mask = case
    eq, _ = linearize(state, X, corners, mask)
    free = np.ones(state.s.size, bool)
    free[0] = False  # the gauge view
    for damping in (0.0, 1e-3):
        d_theta, d_s = solve_arrowhead(eq, free, damping)
        H = np.block([[eq.A, eq.B.T], [eq.B, np.diag(eq.D)]])
        H = H + damping * np.diag(np.diag(H))
        keep = np.r_[np.ones(eq.A.shape[0], bool), free]
        dense = -np.linalg.solve(H[np.ix_(keep, keep)], np.r_[eq.g_theta, eq.g_s][keep])
        assert np.allclose(np.r_[d_theta, d_s[free]], dense, rtol=1e-8, atol=1e-12)
        assert d_s[0] == 0.0


def test_a_gauss_newton_step_lowers_the_cost(case):
    state, X, corners, mask = case
    eq, _ = linearize(state, X, corners, mask)
    free = np.ones(state.s.size, bool)
    free[0] = False
    d_theta, d_s = solve_arrowhead(eq, free)
    after = apply_step(state, d_theta, d_s, eq.basis)
    assert np.linalg.norm(after.n) == pytest.approx(1.0)
    assert np.allclose(after.R @ after.R.T, np.eye(3), atol=1e-12)
    assert linearize(after, X, corners, mask)[0].ssr < eq.ssr
