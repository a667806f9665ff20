"""An extreme over noisy values (max |angle|, max |deviation|, a p-v over targets) and its U against the truth
(issue 35: max |roll| over 48 views covered in 50 %, a row's EBX p-v in 20 %: the max picks the noise)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from lps_gui.core.metrology.extreme_noise import corrected_extreme
from lps_gui.core.metrology.iso230_noise import noise_corrected_max_abs
from lps_gui.core.metrology.resolution import max_abs_resolution, profile_span
from lps_gui.core.metrology.uncertainty_budget import (
    extreme_uncertainties,
    iso_noise_uncertainties,
)

TRIALS = 30


def _profile(rng: np.random.Generator, x: np.ndarray, amplitude: float) -> np.ndarray:
    """A smooth error profile of random phase and period (the campaign's stages: one or two waves)."""
    return amplitude * np.sin(2.0 * np.pi * x / rng.uniform(20.0, 60.0) + rng.uniform(0.0, 2.0 * np.pi))


def _coverage(seed: int, x: np.ndarray, amplitude: float, z_of: Callable[..., float]) -> tuple[float, float]:
    """Coverage of U (k = 2) and mean (error/sigma)^2 over ``TRIALS`` profiles: ``z_of(rng, truth)`` measures one."""
    rng = np.random.default_rng(seed)
    z = np.array([z_of(rng, _profile(rng, x, amplitude)) for _ in range(TRIALS)])
    return float(np.mean(np.abs(z) <= 2.0)), float(np.mean(z**2))


def test_max_abs_angle_over_noisy_views_is_covered_by_its_u():
    """48 views (12 stops x 4) of a roll profile 5 x the per-view sigma: the max |x| picked the noise (before,
    the raw max and U = k x the median sigma: coverage 80 %, mean z^2 3.0 on these draws); now U holds."""
    x = np.repeat(np.linspace(0.0, 22.0, 12), 4)
    sigma = np.full(x.size, 400.0)

    def z_of(rng: np.random.Generator, truth: np.ndarray) -> float:
        r = max_abs_resolution(truth + sigma * rng.standard_normal(x.size), sigma, x, np.ones(x.size, bool))
        U = extreme_uncertainties({"angles_resolution": {"roll": r}}, 2.0, {"roll": 400.0})["max_abs_roll"]
        return (r["max_abs_urad"] - np.max(np.abs(truth - truth.mean()))) / (U / 2.0)  # about the mean attitude

    coverage, z2 = _coverage(35, x, 2000.0, z_of)
    assert coverage >= 0.9 and 0.4 <= z2 <= 2.0, (coverage, z2)


def test_max_abs_angle_near_the_noise_is_the_max_of_the_stops_means():
    """The campaign's pitch on the motions stage: a ramp of +-660 urad over 12 stops x 4 views, 300 urad a view.
    The max over single views is mostly the noise's own max (measured 1.1-1.7 mrad): resolved in 16 of these 30
    draws on main, and 6 of 10 line-both sessions (83 % covered). Of the stops' means (noise / 2, 12 draws not
    48) it is a finding in most draws, and still honest."""
    x = np.repeat(np.linspace(0.0, 22.0, 12), 4)
    sigma = np.full(x.size, 300.0)
    truth = np.repeat(np.linspace(-660.0, 660.0, 12), 4)
    rng = np.random.default_rng(37)
    z = []
    for _ in range(TRIALS):
        r = max_abs_resolution(truth + sigma * rng.standard_normal(x.size), sigma, x, np.ones(x.size, bool))
        U = extreme_uncertainties({"angles_resolution": {"pitch": r}}, 2.0, {"pitch": 300.0})["max_abs_pitch"]
        if r["resolved"]:
            z.append((r["max_abs_urad"] - 660.0) / (U / 2.0))
    z2 = float(np.mean(np.square(z)))
    assert len(z) >= 0.8 * TRIALS and np.mean(np.abs(z) <= 2.0) >= 0.9 and 0.5 <= z2 <= 2.0, (len(z), z2)


def test_span_over_many_targets_is_covered_by_its_u():
    """A p-v over 40 per-target means of a profile 1.5 x their sigma (a row's angles over its stops): the p-v
    of the means picked the noise (before, the raw p-v and U = k sqrt 2 sigma: coverage 40 %, mean z^2 4.2 on
    these draws); the span and its U now hold (a little wide here: mean z^2 0.44)."""
    x = np.linspace(0.0, 40.0, 40)
    sigma = np.full(x.size, 10.0)

    def z_of(rng: np.random.Generator, truth: np.ndarray) -> float:
        span = profile_span(truth + sigma * rng.standard_normal(x.size), sigma, x, np.ones(x.size, bool))
        U = extreme_uncertainties({"straightness": {"v1": span.to_dict("um")}}, 2.0, {})["straightness_span_1"]
        return (span.span - np.ptp(truth)) / (U / 2.0)

    coverage, z2 = _coverage(36, x, 15.0, z_of)
    assert coverage >= 0.9 and 0.3 <= z2 <= 2.0, (coverage, z2)


def test_max_abs_deviation_takes_out_the_noise_and_its_reference():
    """Deviations relative to a reference capture (its noise common to all) of a profile 2 x their sigma:
    max |deviation| and its U (before, the raw max and U = k sigma: coverage 77 %, mean z^2 2.9 on these draws)."""
    x = np.repeat(np.linspace(0.0, 22.0, 12), 4)

    def z_of(rng: np.random.Generator, truth: np.ndarray) -> float:
        measured = truth + 2.1 * rng.standard_normal(x.size) + 2.1 * rng.standard_normal()
        figures = {"single_run": noise_corrected_max_abs(measured, np.ones(x.size, bool), np.full(x.size, 3.0))}
        U = iso_noise_uncertainties({"budget": []}, figures, 2.0)["max_abs_deviation_um"]
        return (figures["single_run"]["max_abs_deviation_um"] - np.max(np.abs(truth))) / (U / 2.0)

    coverage, z2 = _coverage(37, x, 6.0, z_of)
    assert coverage >= 0.85 and 0.4 <= z2 <= 1.5, (coverage, z2)


def test_the_correction_is_deterministic_and_takes_correlated_noise():
    """Same data, same figure; a factor of a correlated covariance is drawn as such (a common offset moves no
    p-v: the span of values whose noise is one shared offset is not corrected)."""
    v = np.array([0.0, 3.0, 1.0, -2.0, 0.5])
    a, b = corrected_extreme(v, np.ones(5), "span"), corrected_extreme(v, np.ones(5), "span")
    assert a == b and a.bias > 0 and a.corrected < a.measured
    common = corrected_extreme(v, np.ones((5, 1)), "span")
    assert abs(common.bias) < 1e-9 and abs(common.corrected - 5.0) < 1e-9
    assert corrected_extreme(np.array([1.0, np.nan]), np.ones(2)) is None


def test_a_bow_is_not_read_as_noise_of_its_span():
    """The honesty campaign's line-both geometry (12 targets over 22 mm, 4 views each, 1.9 um a view) with a
    ~1.1 mm roll bow (a wave of 40-80 mm): second differences read the bow's curvature as 28 um of noise per
    mean, U of the span ~116 um on errors of ~1 um (before: mean z^2 ~0.002 on these draws); fourth ones do not
    (0.26: the extreme's u is 1.5 x its spread by design, core/metrology/extreme_noise.py)."""
    x = np.repeat(np.linspace(0.0, 22.0, 12), 4)
    sigma = np.full(x.size, 1.9)
    rng = np.random.default_rng(38)
    z = []
    for _ in range(TRIALS):
        truth = 560.0 * np.sin(2.0 * np.pi * x / rng.uniform(40.0, 80.0) + rng.uniform(0.0, 2.0 * np.pi))
        span = profile_span(truth + sigma * rng.standard_normal(x.size), sigma, x, np.ones(x.size, bool),
                            difference_order=4)
        U = extreme_uncertainties({"straightness": {"v1": span.to_dict("um")}}, 2.0, {})["straightness_span_1"]
        z.append((span.span - np.ptp(truth)) / (U / 2.0))
    z2 = float(np.mean(np.square(z)))
    assert np.mean(np.abs(z) <= 2.0) >= 0.9 and 0.15 <= z2 <= 2.0, z2


def test_a_rotation_read_as_a_displacement_is_overstated_by_the_corners_field_angle():
    """Exact projection of a 9 x 6 board at 500 mm before and after a camera rotation w about its x axis: the
    displacement that moves the corners most alike (least squares) is Z w (1 + f), f the corners' mean squared
    normalized y (:func:`rotation_read_as_shift`, 0.46 % on the campaign's motions stage), not Z w."""
    from lps_gui.core.geometry.camera_model import CameraIntrinsics
    from lps_gui.core.models.constant_orientation import rotation_read_as_shift

    K = np.array([[600.0, 0.0, 322.0], [0.0, 600.0, 238.0], [0.0, 0.0, 1.0]])
    gx, gy = np.meshgrid(np.arange(9) * 20.0 - 40.0, np.arange(6) * 20.0 - 33.0)
    X = np.c_[gx.ravel(), gy.ravel(), np.full(gx.size, 500.0)]  # camera frame, board centre ~17 mm off axis
    w = 2e-3
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(w), -np.sin(w)], [0.0, np.sin(w), np.cos(w)]])

    def image(P: np.ndarray) -> np.ndarray:
        return P[:, :2] / P[:, 2:]

    shift_y = image(X @ Rx.T)[:, 1] - image(X)[:, 1]  # normalized; a displacement t along y moves each by t / Z
    read = abs(500.0 * float(np.mean(shift_y)))  # least-squares displacement (all corners at Z)
    f = rotation_read_as_shift((image(X) * 600.0 + K[:2, 2])[None], CameraIntrinsics((640, 480), K, np.zeros(5)),
                               np.array([[0.0], [1.0], [0.0]]))[0]
    assert abs(read / (500.0 * np.tan(w)) - 1.0 - f) < 0.05 * f and f > 0.003
    spans = extreme_uncertainties({"straightness": {"v1": {"u_span_um": 1.0, "u_model_um": f * 1160.0}}}, 2.0, {})
    assert abs(spans["straightness_span_1"] - 2.0 * np.hypot(1.0, f * 1160.0)) < 1e-9
