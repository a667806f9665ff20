"""core/models/joint_lm: Huber weights in the normal equations; the Schur step against a dense solve.

The normal equations against central finite differences: tests/core/test_gradients.py (every model).
"""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.models.joint_lm import apply_step, huber_weights, linearize, robust_cost, solve_arrowhead
from tests.core.finite_differences import normalized_difference
from tests.core.test_gradients import Case, line_case, line_numeric

TOL = 1e-5  # a Jacobian column scaled by 1.01 moves the normal matrix by ~1e-2 in these units


@pytest.fixture(scope="module")
def case():
    """The line cell of the gradient table: the state near (not at) the truth, noisy corners, a few missing."""
    c = line_case(warp=False)
    return c.state, c.X, c.corners, c.mask


def test_huber_weights_enter_the_normal_equations(case):
    state, X, corners, mask = case
    c = 0.2  # px: many residuals beyond it
    eq, r = linearize(state, X, corners, mask, huber_c=c)
    w = huber_weights(r, mask, c)
    e = np.linalg.norm(r, axis=-1)
    assert np.allclose(w[mask & (e <= c)], 1.0) and np.allclose(w[mask & (e > c)], c / e[mask & (e > c)])
    assert np.all(w[~mask] == 0.0)
    J = line_numeric(Case("line", state, X, corners, mask, ""), with_intrinsics=False)
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
