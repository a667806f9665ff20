"""A planar axis's ISO 230-2 figures are its worst line's: the noise taken out with that choice (issue 35).

Each line's figures, the noise taken out line by line, scatter by their noise; the worst of 4 lines picks
the largest draw, so the per-axis A came out 1.5-3 U above a truth of ~10 um on the point-level
small-planar preset. The truth is a synthetic gantry (known deviations), the camera adds independent noise.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.metrology.planar_figures import planar_figures

REPS = 10  # synthetic sessions of the near-noise test
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


def _short_lines(rng: np.random.Generator, noise_um: float) -> tuple[list, list]:
    """5 lines of 3 targets at 10 mm, both directions, 2 runs (the honesty campaign's planar Y axis): the
    true deviations (A ~10 um) and one noisy measurement of them, as noise_corrected_worst's lines."""
    t = np.tile(np.r_[0.0, 10.0, 20.0, 20.0, 10.0, 0.0], 2)
    d = np.tile(np.r_[np.ones(3), -np.ones(3)], 2)
    run = np.repeat([0, 1], 6) * 2 + (d > 0)
    true, meas = [], []
    for line in range(5):
        x = 3.0 * np.sin(t / 7.0 + line) + 2.0 * (d > 0) + rng.normal(0.0, 1.0, t.size)
        true.append((t, d, run, x, np.full(t.size, 1e-9)))
        meas.append((t, d, run, x + rng.normal(0.0, noise_um, t.size), np.full(t.size, noise_um)))
    return true, meas


def test_the_worst_lines_a_and_r_are_unbiased_where_the_noise_is_near_the_figure() -> None:
    """Noise 8 um a view against A ~10 um (the campaign's planar cell with realism on): with the quadratic
    extrapolant the corrected A and R stayed +25-33 um above the truth (U 46-53 um; 88-90 % covered)."""
    from lps_gui.core.metrology.iso230_noise import noise_corrected_worst

    rng = np.random.default_rng(3)
    err: dict[str, list[float]] = {"A_um": [], "R_um": []}
    U: dict[str, list[float]] = {"A_um": [], "R_um": []}
    for _ in range(REPS):
        true, meas = _short_lines(rng, 8.0)
        truth = noise_corrected_worst(true, draws=40)[1]
        got = noise_corrected_worst(meas, draws=80)[1]
        for key, errors in err.items():
            errors.append(got[key]["corrected"] - truth[key]["corrected"])
            U[key].append(2.0 * got[key]["u_noise"])
    for key, errors in err.items():
        e, u = np.array(errors), np.array(U[key])
        assert abs(e.mean()) < 18.0, (key, e.mean(), u.mean())  # the quadratic extrapolant: A +25, R +28 um
        assert np.mean(np.abs(e) <= u) >= 0.9, key
