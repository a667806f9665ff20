"""Target poses chained from the views that see two targets (SPEC 13), against a known layout."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.rotation import exp_so3, log_so3
from lps_gui.core.geometry.target_chain import chain_targets, tie_counts
from lps_gui.errors import DegenerateGeometryError


def _layout(T: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A row: target j about 340 mm along x of target 0, mounted with small random tilts and offsets."""
    Q = np.stack([np.eye(3)] + [exp_so3(rng.normal(0, 0.02, 3)) for _ in range(T - 1)])
    p = np.array([[340.0 * j, 0.0, 0.0] for j in range(T)]) + np.vstack([np.zeros(3), rng.normal(0, 3, (T - 1, 3))])
    return Q, p


def _views(Q, p, ok, rng, noise_rad=0.0, noise_mm=0.0):
    """Each view's pose of each target: camera pose (R, t) of target 0's frame composed with the target's."""
    K, T = ok.shape
    R = np.zeros((K, T, 3, 3))
    t = np.zeros((K, T, 3))
    for i in range(K):
        Rc = exp_so3(np.array([np.pi, 0, 0]) + rng.normal(0, 0.01, 3))
        tc = np.array([-30.0 * i, 0, 800.0])
        for j in range(T):
            R[i, j] = exp_so3(rng.normal(0, noise_rad, 3)) @ Rc @ Q[j]
            t[i, j] = Rc @ p[j] + tc + rng.normal(0, noise_mm, 3)
    return R, t


def test_a_row_is_chained_from_target_zero_to_the_truth():
    rng = np.random.default_rng(1)
    T, K = 5, 40
    Q, p = _layout(T, rng)
    ok = np.zeros((K, T), bool)
    for i in range(K):  # a moving view sees two neighbours at a time
        j = min(i * (T - 1) // K, T - 2)
        ok[i, j] = ok[i, j + 1] = True
    R, t = _views(Q, p, ok, rng)
    Qe, pe, ties = chain_targets(R, t, ok, [f"T{j}" for j in range(T)], [f"v{i}.png" for i in range(K)])
    np.testing.assert_allclose(pe, p, atol=1e-9)
    for j in range(T):
        assert np.linalg.norm(log_so3(Qe[j].T @ Q[j])) < 1e-9
    assert ties[0, 1] > 0 and ties[0, 2] == 0


def test_noisy_views_average_towards_the_truth():
    rng = np.random.default_rng(2)
    T, K = 3, 300
    Q, p = _layout(T, rng)
    ok = np.ones((K, T), bool)
    R, t = _views(Q, p, ok, rng, noise_rad=1e-3, noise_mm=0.5)
    Qe, pe, _ = chain_targets(R, t, ok, ["A", "B", "C"], [str(i) for i in range(K)])
    # each edge averages 300 views: the error falls about as 1/sqrt(300) of one view's (plus rotation lever)
    assert np.abs(pe - p).max() < 0.5
    for j in range(T):
        assert np.linalg.norm(log_so3(Qe[j].T @ Q[j])) < 3e-4


def test_the_chain_runs_through_the_best_tied_pairs():
    rng = np.random.default_rng(3)
    Q, p = _layout(3, rng)
    ok = np.zeros((30, 3), bool)
    ok[:10, [0, 1]] = True  # ties 0-1: 10
    ok[10:15, [0, 2]] = True  # ties 0-2: 5 (these views are corrupted below)
    ok[15:, [1, 2]] = True  # ties 1-2: 15, preferred over 0-2
    R, t = _views(Q, p, ok, rng)
    t[10:15, 2, 0] += 50.0
    _, pe, ties = chain_targets(R, t, ok, ["T0", "T1", "T2"], [str(i) for i in range(30)])
    assert (ties[0, 1], ties[0, 2], ties[1, 2]) == (10, 5, 15)
    np.testing.assert_allclose(pe[2], p[2], atol=1e-9)


def test_an_untied_target_is_named_with_the_views_that_saw_it():
    rng = np.random.default_rng(4)
    Q, p = _layout(3, rng)
    ok = np.zeros((6, 3), bool)
    ok[:3, 0] = ok[:3, 1] = True
    ok[4:, 2] = True
    R, t = _views(Q, p, ok, rng)
    names = [f"img{i}.png" for i in range(6)]
    with pytest.raises(DegenerateGeometryError) as err:
        chain_targets(R, t, ok, ["T0", "T1", "T2"], names)
    msg = str(err.value)
    assert "target T2 is not tied to target T0" in msg and "img4.png, img5.png" in msg and "\n" not in msg


def test_a_target_never_seen_is_named():
    ok = np.zeros((2, 2), bool)
    ok[:, 0] = True
    R = np.tile(np.eye(3), (2, 2, 1, 1))
    t = np.zeros((2, 2, 3))
    with pytest.raises(DegenerateGeometryError, match="target T1 was not found in any view"):
        chain_targets(R, t, ok, ["T0", "T1"], ["a", "b"])


def test_tie_counts_are_views_seen_together():
    ok = np.array([[1, 1, 0], [0, 1, 1], [1, 1, 1]], bool)
    np.testing.assert_array_equal(tie_counts(ok), [[2, 2, 1], [2, 3, 2], [1, 2, 2]])
