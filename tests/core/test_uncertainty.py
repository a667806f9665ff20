"""core/numerics/arrowhead and core/numerics/uncertainty: the Schur step and the factored inverse against dense algebra for
blocks of b = 1 (line), 2 (plane) and 6 (poses); noise variance; propagation."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.models.joint_lm import line_inverse
from lps_gui.core.numerics.arrowhead import arrowhead_inverse, intrinsics_sensitivity, schur_step
from lps_gui.core.numerics.uncertainty import noise_variance, propagated_variance
from lps_gui.errors import DegenerateGeometryError


def random_arrowhead(rng, b=1, p=8, K=12):
    """A well-conditioned SPD block arrowhead H = J^T J: A (p, p), B (K, b, p), D (K, b, b)."""
    Jt = rng.normal(size=(K, 20, p))  # each view's residuals against the shared parameters
    js = rng.normal(size=(K, 20, b))  # ... and against its own b unknowns
    return (np.einsum("kri,krj->ij", Jt, Jt), np.einsum("kra,kri->kai", js, Jt),
            np.einsum("kra,krc->kac", js, js))


def dense_matrix(A, B, D):
    K, b, p = B.shape
    H = np.zeros((p + K * b, p + K * b))
    H[:p, :p] = A
    H[p:, :p] = B.reshape(K * b, p)
    H[:p, p:] = H[p:, :p].T
    for k in range(K):
        H[p + k * b: p + (k + 1) * b, p + k * b: p + (k + 1) * b] = D[k]
    return H


def dense(A, B, D, free):
    """H^-1 with the held views' rows and columns zero."""
    K, b, p = B.shape
    H = dense_matrix(A, B, D)
    keep = np.r_[np.ones(p, bool), np.repeat(free, b)]
    inv = np.zeros_like(H)
    inv[np.ix_(keep, keep)] = np.linalg.inv(H[np.ix_(keep, keep)])
    return inv


def views(M, p, K, b):
    """The (K, b, K, b) view block of a dense (p + K b) square matrix."""
    return M[p:, p:].reshape(K, b, K, b)


@pytest.mark.parametrize("b", [1, 2, 6])
@pytest.mark.parametrize("seed", range(2))
def test_arrowhead_inverse_equals_the_dense_inverse(seed, b):
    rng = np.random.default_rng(seed)
    A, B, D = random_arrowhead(rng, b)
    K, p = B.shape[0], B.shape[2]
    free = np.ones(K, bool)
    free[[0, 5]] = False  # the gauge view and an excluded one
    inv = arrowhead_inverse(A, B, D, free)
    Hi = dense(A, B, D, free)
    V = views(Hi, p, K, b)
    assert np.allclose(inv.S_inv, Hi[:p, :p], rtol=1e-9, atol=1e-14)
    assert np.allclose(inv.cov_view(), np.einsum("kakc->kac", V), rtol=1e-9, atol=1e-14)
    i, j = np.array([1, 2, 3, 7]), np.array([2, 2, 9, 11])
    assert np.allclose(inv.cov_between(i, j), V[i, :, j, :], rtol=1e-9, atol=1e-14)
    step = V[i, :, i, :] + V[j, :, j, :] - V[i, :, j, :] - np.swapaxes(V[i, :, j, :], 1, 2)
    assert np.allclose(inv.cov_difference(i, j), step, rtol=1e-9, atol=1e-14)
    rt, rs = rng.normal(size=(p, 2)), rng.normal(size=(K, b, 2)) * free[:, None, None]
    yt, ys = inv.solve(rt, rs)
    y = Hi @ np.r_[rt, rs.reshape(K * b, 2)]
    assert np.allclose(np.r_[yt, ys.reshape(K * b, 2)], y, rtol=1e-9, atol=1e-12)
    L = rng.normal(size=(3, K, b))
    Lf = np.c_[np.zeros((3, p)), L.reshape(3, K * b)]
    assert np.allclose(inv.functional_covariance(L), Lf @ Hi @ Lf.T, rtol=1e-9, atol=1e-14)


@pytest.mark.parametrize("b", [1, 2, 6])
def test_the_damped_schur_step_solves_the_damped_system_with_held_views(b):
    rng = np.random.default_rng(3)
    A, B, D = random_arrowhead(rng, b)
    K, p = B.shape[0], B.shape[2]
    free = np.ones(K, bool)
    free[[0, 4]] = False
    g_theta, g_s = rng.normal(size=p), rng.normal(size=(K, b))
    lam = 0.3
    d_theta, d_s = schur_step(A, B, D, g_theta, g_s, free, lam)
    H = dense_matrix(A, B, D)
    H = H + lam * np.diag(np.diag(H))
    keep = np.r_[np.ones(p, bool), np.repeat(free, b)]
    x = np.zeros(p + K * b)
    x[keep] = -np.linalg.solve(H[np.ix_(keep, keep)], np.r_[g_theta, g_s.ravel()][keep])
    assert np.allclose(np.r_[d_theta, d_s.ravel()], x, rtol=1e-9, atol=1e-12)
    assert not d_s[~free].any()


@pytest.mark.parametrize("b", [1, 2])
def test_intrinsics_sensitivity_and_propagation_match_dense_algebra(b):
    rng = np.random.default_rng(7)
    A, B, D = random_arrowhead(rng, b)
    K, p = B.shape[0], B.shape[2]
    free = np.ones(K, bool)
    free[0] = False
    inv = arrowhead_inverse(A, B, D, free)
    cross_theta, cross_s = rng.normal(size=(p, 9)), rng.normal(size=(K, b, 9)) * free[:, None, None]
    G_s = intrinsics_sensitivity(inv, cross_theta, cross_s)
    G = -dense(A, B, D, free) @ np.r_[cross_theta, cross_s.reshape(K * b, 9)]
    assert np.allclose(G_s.reshape(K * b, 9), G[p:], rtol=1e-9, atol=1e-12)
    L = rng.normal(size=(9, 9))
    cov_I = L @ L.T
    assert np.allclose(propagated_variance(G_s[:, 0], cov_I), np.diag(G[p::b] @ cov_I @ G[p::b].T))


def test_a_singular_line_is_a_clear_error():
    rng = np.random.default_rng(0)
    A, B, D = random_arrowhead(rng)
    A[:, 0] = A[0, :] = 0.0  # one shared parameter the data do not see
    B[..., 0] = 0.0
    with pytest.raises(DegenerateGeometryError, match="do not determine the line"):
        line_inverse(A, B[:, 0], D[:, 0, 0], np.ones(len(D), bool))


def test_noise_variance_counts_degrees_of_freedom():
    assert noise_variance(90.0, 100, 10) == pytest.approx(1.0)
    with pytest.raises(DegenerateGeometryError, match="no redundancy"):
        noise_variance(1.0, 10, 10)
