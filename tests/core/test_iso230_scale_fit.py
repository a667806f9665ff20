"""The scale fit's closed form (group-centred targets) against the SVD / lstsq of its design it replaced."""
import numpy as np
import pytest

from lps_gui.core.metrology.iso230_run import _scale_fit, scale_functional


def _design(t, group):
    _, g = np.unique(group, return_inverse=True)
    design = np.zeros((t.size, 1 + int(g.max()) + 1))
    design[:, 0] = t - t.mean()
    design[np.arange(t.size), 1 + g.ravel()] = 1.0
    return design


def _reference_functional(t, group, w=None):
    design = _design(t, group)
    sw = np.ones_like(t) if w is None else np.sqrt(w)
    if np.linalg.matrix_rank(design * sw[:, None]) < design.shape[1]:
        return None
    return np.linalg.pinv(design * sw[:, None])[0] * sw


def _reference_fit(t, x, w, group):
    design = _design(t, group)
    sw = np.ones_like(t) if w is None else np.sqrt(w)
    coef, *_ = np.linalg.lstsq(design * sw[:, None], x * sw, rcond=None)
    resid = x - design @ coef
    row = _reference_functional(t, group, w)
    if row is None:
        return resid, None, None
    dof = t.size - design.shape[1]
    if dof <= 0:
        return resid, float(row @ x), None
    chi2_red = float(np.sum(sw**2 * resid**2) / dof)
    var = float(np.sum(row**2 / (sw**2))) * (chi2_red if w is None else max(1.0, chi2_red))
    return resid, float(row @ x), float(np.sqrt(var))


@pytest.mark.parametrize("weighted", [False, True])
@pytest.mark.parametrize("runs", [1, 3, 10])
def test_same_row_slope_sigma_and_residual_as_the_svd(weighted, runs):
    rng = np.random.default_rng(runs)
    targets = np.arange(0.0, 200.0, 2.0)
    t = np.tile(targets, 2 * runs)
    group = np.repeat(np.arange(2 * runs), targets.size)
    x = 25e-3 * t + rng.normal(0.0, 1.0, t.size) + 3.0 * (group % 2)  # scale, noise, backlash
    keep = rng.random(t.size) > 0.1  # missing captures
    t, x, group = t[keep], x[keep], group[keep]
    w = 1.0 / rng.uniform(0.5, 2.0, t.size) ** 2 if weighted else None
    np.testing.assert_allclose(scale_functional(t, group, w), _reference_functional(t, group, w), rtol=1e-9,
                               atol=1e-12 / t.size)
    resid, b, sb = _scale_fit(t, x, w, group)
    r_resid, r_b, r_sb = _reference_fit(t, x, w, group)
    np.testing.assert_allclose(resid, r_resid, rtol=0, atol=1e-10)
    assert b == pytest.approx(r_b, rel=1e-12) and sb == pytest.approx(r_sb, rel=1e-10)


def test_one_target_per_group_determines_no_slope():
    t = np.array([0.0, 10.0, 20.0])
    group = np.array([0, 1, 2])
    x = np.array([1.0, 2.0, 4.0])
    assert scale_functional(t, group) is None and _reference_functional(t, group) is None
    resid, b, sb = _scale_fit(t, x, None, group)
    assert b is None and sb is None
    np.testing.assert_allclose(resid, _reference_fit(t, x, None, group)[0], atol=1e-12)


def test_as_many_targets_as_parameters_gives_a_slope_without_sigma():
    t, group, x = np.array([0.0, 10.0]), np.array([0, 0]), np.array([1.0, 3.0])
    resid, b, sb = _scale_fit(t, x, None, group)
    assert b == pytest.approx(0.2) and sb is None
    np.testing.assert_allclose(resid, 0.0, atol=1e-12)
