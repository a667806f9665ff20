"""The noise Monte Carlo's figures through a remembered plan are bidirectional_figures' own, exactly.

iso230_noise groups a plan's captures into approaches once and reuses the
grouping for every draw (lps_gui/core/metrology/iso230_noise.py, _plan_of);
draws of several plans in turn (a planar axis's lines) must not mix them up,
and a draw with a NaN deviation where the plan had a value takes the full path.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.metrology import iso230_noise
from lps_gui.core.metrology.iso230 import bidirectional_figures


def _plan(rng: np.random.Generator, targets: int, runs: int, frames: int, both: bool, named_runs: bool):
    t, d, r = [], [], []
    for run in range(runs):
        for s in ((1, -1) if both else (1,)):
            for j in range(targets)[::s]:
                t += [2.5 * j + rng.normal(0, 1e-8)] * frames  # within the target tolerance: one target
                d += [s] * frames
                r += [f"run {run}" if named_runs else run] * frames
    valid = rng.random(len(t)) > 0.1
    return np.array(t), np.array(d), np.array(r), valid


def _scratch(t, d, r, x, valid) -> np.ndarray:
    fig = bidirectional_figures(t, d, r, x, valid)
    return np.array([np.nan if fig is None or getattr(fig, k) is None else float(getattr(fig, k))
                     for k in iso230_noise.NOISE_KEYS])


def test_draws_of_interleaved_plans_give_the_figures_of_a_fresh_computation() -> None:
    rng = np.random.default_rng(11)
    plans = [_plan(rng, 6, 3, 1, True, False), _plan(rng, 6, 3, 1, True, True),  # same shape, other run names
             _plan(rng, 9, 2, 2, True, False), _plan(rng, 5, 4, 1, False, False), _plan(rng, 4, 1, 1, True, False)]
    iso230_noise._PLANS.clear()
    checked = 0
    for _ in range(20):
        for t, d, r, valid in plans:  # in turn, as noise_corrected_worst draws a planar axis's lines
            x = 3 * np.sin(t) + rng.normal(0, 2, t.size)
            got = iso230_noise._figure_vector(t, d, r, x, valid)
            want = _scratch(t, d, r, x, valid)
            assert np.array_equal(got, want, equal_nan=True), (got, want)
            checked += int(np.isfinite(want).sum())
    assert checked > 500  # most figures are defined: the comparison is not of NaNs
    assert 0 < len(iso230_noise._PLANS) <= len(plans)


def test_a_nan_deviation_of_a_valid_capture_is_left_out_as_bidirectional_figures_does() -> None:
    rng = np.random.default_rng(12)
    t, d, r, valid = _plan(rng, 6, 3, 1, True, False)
    x = rng.normal(0, 2, t.size)
    iso230_noise._figure_vector(t, d, r, x, valid)  # the plan is remembered with every valid deviation finite
    x[np.flatnonzero(valid)[3]] = np.nan
    got = iso230_noise._figure_vector(t, d, r, x, valid)
    assert np.array_equal(got, _scratch(t, d, r, x, valid), equal_nan=True)
    assert not np.array_equal(got, _scratch(t, d, r, np.nan_to_num(x), valid), equal_nan=True)
