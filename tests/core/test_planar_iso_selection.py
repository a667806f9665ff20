"""A planar axis's ISO 230-2 figures are its worst line's: the noise taken out with that choice (issue 35).

Each line's figures, the noise taken out line by line, scatter by their noise; the worst of 4 lines picks
the largest draw, so the per-axis A came out 1.5-3 U above a truth of ~10 um on the point-level
small-planar preset. The truth is a synthetic gantry (known deviations), the camera adds independent noise.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.metrology.planar_figures import planar_figures

NOISE_UM = 30.0  # per view, against a stage whose A is ~13 um: the small-planar preset's regime


def _grid(seed: int) -> tuple:
    """4 lines of 6 targets along X at 10 mm, both directions, 2 runs; true and measured deviations."""
    rng = np.random.default_rng(seed)
    t, appr, run = [], [], []
    for r in range(2):
        for sign in (1, -1):
            for y in np.arange(4) * 10.0:
                for x in (np.arange(6) * 10.0)[::sign]:
                    t.append((x, y))
                    appr.append((sign, 1.0))
                    run.append(r)
    t, appr, run = np.array(t), np.array(appr), np.array(run)
    true = np.stack([3 * np.sin(t[:, 0] / 7) + 2.0 * (appr[:, 0] > 0), np.zeros(len(t))], axis=1)
    true += rng.normal(0.0, 1.0, t.shape)  # the stage's repeatability
    measured = true + rng.normal(0.0, NOISE_UM, t.shape)
    sigma = np.full(t.shape, NOISE_UM * np.sqrt(2.0))  # against the reference view: half of it is the reference's
    return (t, appr, run, appr[:, 0]), true, measured, sigma


def _axis_iso(figs) -> dict:
    return figs.per_axis["X"]["iso230_2"]["iso230_2"]


def test_the_worst_lines_figures_are_corrected_with_the_choice_of_line() -> None:
    plan, true, measured, sigma = _grid(seed=0)
    ok = np.ones(len(true), bool)
    est = planar_figures(*plan, measured, sigma, ok, np.eye(2), np.zeros((4, 4)))
    truth = planar_figures(*plan, true, np.full_like(true, 1e-6), ok, np.eye(2), np.zeros((4, 4)))
    iso, true_iso = _axis_iso(est), _axis_iso(truth)
    for key in ("A_um", "R_um"):
        c = iso["noise_correction"][key]
        assert c["selection"] == 4  # the worst of the 4 lines, chosen again in every Monte Carlo draw
        assert c["measured"] > true_iso[key] + 4 * c["u_noise"] / 2 or c["measured"] > 5 * true_iso[key]  # noise-made
        assert abs(iso[key] - true_iso[key]) <= 2 * c["u_noise"], key  # U (k = 2) covers the truth
    assert abs(true_iso["noise_correction"]["A_um"]["bias"]) < 1e-3  # the truth has no noise to take out
