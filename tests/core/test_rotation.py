"""core/geometry/rotation: exp/log are inverse, the left perturbation's derivative, the chordal mean."""
from __future__ import annotations

import numpy as np

from lps_gui.core.geometry.rotation import chordal_mean, exp_so3, log_so3, project_to_so3, skew
from tests.core.finite_differences import central_jacobian


def test_skew_is_the_cross_product():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    assert np.allclose(skew(a) @ b[..., None], np.cross(a, b)[..., None])
    assert np.allclose(skew(a), -np.swapaxes(skew(a), -1, -2))


def test_exp_and_log_are_inverse_and_vectorized():
    rng = np.random.default_rng(1)
    w = rng.normal(size=(4, 6, 3)) * 0.8
    R = exp_so3(w)
    assert R.shape == (4, 6, 3, 3)
    assert np.allclose(np.einsum("...ji,...jk->...ik", R, R), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.allclose(log_so3(R), w, atol=1e-12)


def test_left_perturbation_derivative_is_minus_skew_of_the_rotated_point():
    """The solvers' rotation column: d (exp(w) R X) / d w at w = 0 is -[R X]x."""
    rng = np.random.default_rng(2)
    R, X = exp_so3(rng.normal(size=3)), rng.normal(size=3) * 100
    J = central_jacobian(lambda w: exp_so3(w) @ R @ X, 3, 1e-6)
    assert np.allclose(J, -skew(R @ X), rtol=1e-8, atol=1e-8)


def test_project_to_so3_and_chordal_mean():
    rng = np.random.default_rng(3)
    R0 = exp_so3(rng.normal(size=3))
    assert np.allclose(project_to_so3(1.7 * R0), R0)
    noisy = np.einsum("kij,jl->kil", exp_so3(rng.normal(size=(200, 3)) * 1e-3), R0)
    M = chordal_mean(noisy)
    assert np.linalg.norm(log_so3(M @ R0.T)) < 3e-4  # ~ 1e-3 / sqrt(200) * sqrt(3)
    # weights: a view with zero weight does not move the mean
    w = np.ones(201)
    w[-1] = 0.0
    far = np.concatenate([noisy, exp_so3(np.array([[0.0, 0.0, 0.5]])) @ R0])
    assert np.allclose(chordal_mean(far, w), M)
