"""core/uncertainty: the factored arrowhead inverse against a dense inverse; noise variance; propagation."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.uncertainty import arrowhead_inverse, intrinsics_sensitivity, noise_variance, propagated_variance
from lps_gui.errors import DegenerateGeometryError


def random_arrowhead(rng, p=8, K=12):
    """A well-conditioned SPD arrowhead matrix H = J^T J with a diagonal s-block."""
    Jt = rng.normal(size=(K, 20, p))  # each view's residuals against the shared parameters
    js = rng.normal(size=(K, 20))  # ... and against its own position
    A = np.einsum("kri,krj->ij", Jt, Jt)
    B = np.einsum("kri,kr->ki", Jt, js)
    D = np.einsum("kr,kr->k", js, js)
    return A, B, D


def dense(A, B, D, free):
    p = A.shape[0]
    H = np.block([[A, B.T], [B, np.diag(D)]])
    keep = np.r_[np.ones(p, bool), free]
    inv = np.zeros_like(H)
    inv[np.ix_(keep, keep)] = np.linalg.inv(H[np.ix_(keep, keep)])
    return inv


@pytest.mark.parametrize("seed", range(3))
def test_arrowhead_inverse_equals_the_dense_inverse(seed):
    rng = np.random.default_rng(seed)
    A, B, D = random_arrowhead(rng)
    K, p = B.shape
    free = np.ones(K, bool)
    free[[0, 5]] = False  # the gauge view and an excluded one
    inv = arrowhead_inverse(A, B, D, free)
    Hi = dense(A, B, D, free)
    assert np.allclose(inv.S_inv, Hi[:p, :p], rtol=1e-9, atol=1e-14)
    assert np.allclose(inv.var_s(), np.diag(Hi)[p:], rtol=1e-9, atol=1e-14)
    i, j = np.array([1, 2, 3, 7]), np.array([2, 2, 9, 11])
    assert np.allclose(inv.cov_s(i, j), Hi[p + i, p + j], rtol=1e-9, atol=1e-14)
    var_step = Hi[p + i, p + i] + Hi[p + j, p + j] - 2 * Hi[p + i, p + j]
    assert np.allclose(inv.var_difference(i, j), var_step, rtol=1e-9, atol=1e-14)
    rt, rs = rng.normal(size=(p, 2)), rng.normal(size=(K, 2)) * free[:, None]
    yt, ys = inv.solve(rt, rs)
    y = Hi @ np.r_[rt, rs]
    assert np.allclose(np.r_[yt, ys], y, rtol=1e-9, atol=1e-12)


def test_intrinsics_sensitivity_and_propagation_match_dense_algebra():
    rng = np.random.default_rng(7)
    A, B, D = random_arrowhead(rng)
    K, p = B.shape
    free = np.ones(K, bool)
    free[0] = False
    inv = arrowhead_inverse(A, B, D, free)
    cross_theta, cross_s = rng.normal(size=(p, 9)), rng.normal(size=(K, 9)) * free[:, None]
    G_theta, G_s = intrinsics_sensitivity(inv, cross_theta, cross_s)
    G = -dense(A, B, D, free) @ np.r_[cross_theta, cross_s]
    assert np.allclose(np.r_[G_theta, G_s], G, rtol=1e-9, atol=1e-12)
    L = rng.normal(size=(9, 9))
    cov_I = L @ L.T
    assert np.allclose(propagated_variance(G_s, cov_I), np.diag(G[p:] @ cov_I @ G[p:].T))


def test_a_singular_line_is_a_clear_error():
    rng = np.random.default_rng(0)
    A, B, D = random_arrowhead(rng)
    A[:, 0] = A[0, :] = 0.0  # one shared parameter the data do not see
    B[:, 0] = 0.0
    with pytest.raises(DegenerateGeometryError, match="do not determine the line"):
        arrowhead_inverse(A, B, D, np.ones(len(D), bool))


def test_noise_variance_counts_degrees_of_freedom():
    assert noise_variance(90.0, 100, 10) == pytest.approx(1.0)
    with pytest.raises(DegenerateGeometryError, match="no redundancy"):
        noise_variance(1.0, 10, 10)


def test_the_line_inverse_is_the_block_inverse_with_one_unknown_per_view():
    """One uncertainty for every D: the scalar arrowhead of a line is the block arrowhead of b = 1 (the
    planar path's), for the covariances and the intrinsics' sensitivity alike."""
    from lps_gui.core.block_arrowhead import block_arrowhead_inverse, block_intrinsics_sensitivity

    rng = np.random.default_rng(7)
    A, B, D = random_arrowhead(rng)
    free = np.ones(D.size, bool)
    free[[0, 5]] = False
    line = arrowhead_inverse(A, B, D, free)
    block = block_arrowhead_inverse(A, B[:, None, :], D[:, None, None], free)
    assert np.allclose(block.cov_view()[:, 0, 0], line.var_s(), rtol=1e-12, atol=0)
    L = rng.normal(size=(3, D.size))
    direct = np.einsum("mk,k,nk->mn", L, line.D_inv, L) + (L @ line.W) @ line.S_inv @ (L @ line.W).T
    assert np.allclose(block.functional_covariance(L[:, :, None]), direct, rtol=1e-12)
    cross_theta, cross_s = rng.normal(size=(A.shape[0], 9)), rng.normal(size=(D.size, 9))
    _, G_s = intrinsics_sensitivity(line, cross_theta, cross_s)
    assert np.allclose(block_intrinsics_sensitivity(block, cross_theta, cross_s[:, None, :])[:, 0], G_s, rtol=1e-10,
                       atol=1e-14 * np.abs(G_s).max())
