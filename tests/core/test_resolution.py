"""The one rule for 'resolved' and 'indicative' (core/metrology/resolution.py)."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.metrology.resolution import (
    is_indicative,
    is_resolved,
    noise_max_abs,
    noise_peak_to_valley,
    not_resolved_text,
    profile_span,
    straightness_verdict,
)


def test_noise_bounds_sit_in_the_far_tail_of_pure_noise():
    rng = np.random.default_rng(1)
    for n in (10, 50, 400):
        x = rng.normal(size=(20000, n))
        # mean + 3 sd of the Gumbel limit: 98.5-99.9 % of pure-noise draws stay below
        assert 0.985 < np.mean(np.ptp(x, axis=1) < noise_peak_to_valley(1.0, n)) < 0.999
        assert 0.985 < np.mean(np.abs(x).max(axis=1) < noise_max_abs(1.0, n)) < 0.999


def test_is_resolved_needs_sigma_below_value_and_limit():
    assert is_resolved(10.0, 2.0)
    assert not is_resolved(10.0, 12.0)
    assert not is_resolved(10.0, 2.0, limit=1.5)
    assert not is_resolved(None, 1.0) and not is_resolved(1.0, float("nan"))
    assert not_resolved_text(12.34, "\u00b5m") == "not resolved (noise p-v 12 \u00b5m)"


def test_a_flat_noisy_profile_is_not_resolved_and_a_bow_is():
    rng = np.random.default_rng(2)
    target = np.repeat(np.arange(0.0, 400.0, 20.0), 4)
    sigma = np.full(target.size, 3.0)
    flat = profile_span(rng.normal(0, 3.0, target.size), sigma, target, np.ones(target.size, bool))
    assert not flat.resolved and flat.span < flat.noise_span
    bow = 30.0 * ((target - 200.0) / 200.0) ** 2
    bow -= np.polyval(np.polyfit(target, bow, 1), target)
    found = profile_span(bow + rng.normal(0, 3.0, target.size), sigma, target, np.ones(target.size, bool))
    assert found.resolved and abs(found.span - np.ptp(bow)) < found.noise_span


def test_pose_repeatable_errors_raise_the_per_target_sigma():
    """Captures of one target sharing one error: sigma/sqrt(n) would be too small; second differences see it."""
    rng = np.random.default_rng(3)
    targets = np.arange(0.0, 200.0, 4.0)
    common = rng.normal(0, 3.0, targets.size)
    target = np.repeat(targets, 10)
    values = np.repeat(common, 10) + rng.normal(0, 0.5, target.size)
    span = profile_span(values, np.full(target.size, 0.5), target, np.ones(target.size, bool))
    assert span.sigma > 2.0 and not span.resolved


def test_correlated_noise_is_not_a_finding_and_independent_noise_reads_as_before():
    """A tilt common to the stops' references (a ramp along the travel, as a row of targets' relative tilts
    chain) plus independent noise: a 2.2-sigma ramp's raw p-v is above the independent rule's noise p-v, under
    the noise p-v with the values' full covariance. (With the noise's selection taken out, the independent rule's
    corrected p-v is no finding either: under those sigmas its U exceeds it.)"""
    n = 60
    target = np.arange(n, dtype=float)
    ramp = (target - target.mean()) / (0.5 * np.ptp(target))
    cov = np.outer(ramp, ramp) + 0.2**2 * np.eye(n)
    sigma = np.sqrt(np.diag(cov))
    values = 2.2 * ramp + np.random.default_rng(4).normal(0, 0.2, n)
    ok = np.ones(n, bool)
    independent = profile_span(values, sigma, target, ok)
    assert independent.measured_span > independent.noise_span and independent.span < 2.0 * independent.u_span
    correlated = profile_span(values, sigma, target, ok, covariance=cov)
    assert not correlated.resolved and correlated.noise_span > correlated.span
    # negative control: independent noise and a bow give the same answers with their (diagonal) covariance
    rng = np.random.default_rng(2)
    for truth in (np.zeros(n), 30.0 * ((target - 30.0) / 30.0) ** 2):
        v = truth + rng.normal(0, 3.0, n)
        s = np.full(n, 3.0)
        before, after = profile_span(v, s, target, ok), profile_span(v, s, target, ok, covariance=np.diag(s**2))
        assert before.resolved == after.resolved == bool(truth.any())
        assert abs(after.noise_span / before.noise_span - 1.0) < 0.1


def straightness(v1, n1, v2, n2, r1=True, r2=True):
    return {"straightness": {"basis": "board plane, x", "v1": {"span_um": v1, "noise_span_um": n1, "n_targets": 21,
                                                             "resolved": r1},
                             "v2": {"span_um": v2, "noise_span_um": n2, "n_targets": 21, "resolved": r2}}}


def test_straightness_verdict_branches():
    assert straightness_verdict(straightness(20.0, 4.0, 23.0, 21.0, r2=False), 38.0)["passed"] is True
    assert straightness_verdict(straightness(60.0, 4.0, 10.0, 8.0), 38.0)["passed"] is False
    assert straightness_verdict(straightness(40.0, 4.0, 10.0, 8.0), 38.0)["passed"] is None  # within noise of the limit
    r = straightness_verdict(straightness(20.0, 4.0, 50.0, 61.0, r2=False), 38.0)
    assert r["passed"] is None and "v2 not resolved" in r["note"]
    assert straightness_verdict({}, 38.0) is None


def test_fewer_than_five_runs_per_direction_are_indicative():
    runs = lambda n: {"per_run": [{"run": i, "direction": d} for i in range(n) for d in "+-"]}  # noqa: E731
    assert is_indicative(runs(2)) and not is_indicative(runs(5))


def test_chi2_survival_matches_scipy_stats():
    from scipy.stats import chi2

    from lps_gui.core.metrology.resolution import chi2_sf

    for x, dof in ((3.0, 2), (50.0, 20), (1.0, 7), (400.0, 300)):
        assert chi2_sf(x, dof) == pytest.approx(chi2.sf(x, dof), rel=1e-12)
