"""Numpy versions of the scipy routines the estimate path used to import (issue 15) against scipy itself."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.rotation import exp_so3, log_so3
from lps_gui.core.metrology.iso230_spectrum import deviation_spectrum, sine_amplitude_um


def _rotvecs(rng):
    unit = rng.normal(size=(200, 3))
    unit /= np.linalg.norm(unit, axis=1, keepdims=True)
    return np.concatenate([rng.normal(size=(500, 3)), rng.normal(size=(50, 3)) * 1e-6, np.zeros((1, 3)),
                           rng.normal(size=(50, 3)) * 1e-3, unit[:100] * (np.pi - 1e-9), unit[100:] * 1e-3])


def test_exp_and_log_match_scipy_rotation():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(0)
    rv = _rotvecs(rng)
    R = Rotation.from_rotvec(rv).as_matrix()
    np.testing.assert_allclose(exp_so3(rv), R, atol=1e-15)
    np.testing.assert_allclose(log_so3(R[:-150]), Rotation.from_matrix(R[:-150]).as_rotvec(), atol=1e-14)
    # near pi the sign of the vector is arbitrary: compare the rotations
    np.testing.assert_allclose(exp_so3(log_so3(R)), R, atol=1e-14)
    noisy = R + rng.normal(size=R.shape) * 1e-3  # not orthogonal: both take the nearest rotation
    np.testing.assert_allclose(log_so3(noisy[:600]), Rotation.from_matrix(noisy[:600]).as_rotvec(), atol=1e-12)
    assert exp_so3(np.zeros((2, 5, 3))).shape == (2, 5, 3, 3) and log_so3(np.eye(3)).shape == (3,)


@pytest.mark.parametrize("case", range(4))
def test_sine_amplitude_matches_scipy_lombscargle(case):
    from scipy.signal import lombscargle

    rng = np.random.default_rng(case)
    x = np.sort(rng.uniform(0, 400, 300)) if case % 2 else np.arange(0, 400.0)
    y = 3 * np.sin(2 * np.pi * x / 25.3 + 0.4) + rng.normal(size=x.size) + 7.0
    w = rng.uniform(0.5, 4, x.size) if case >= 2 else None
    freq = np.linspace(1 / 400, 0.45, 300)
    want = np.abs(lombscargle(x, y, 2 * np.pi * freq, normalize="amplitude", floating_mean=True, weights=w))
    np.testing.assert_allclose(sine_amplitude_um(x, y, freq, w), want, rtol=1e-9, atol=1e-12)


def test_spectrum_peak_is_the_simulated_sine():
    rng = np.random.default_rng(5)
    x = np.sort(rng.uniform(0, 400, 300))
    y = 3 * np.sin(2 * np.pi * x / 25.3 + 0.4) + 0.1 * rng.normal(size=x.size)
    sp = deviation_spectrum(x, y)
    assert sp.method == "lomb-scargle"
    assert abs(sp.peak_period_mm - 25.3) < 0.01 and abs(sp.peak_amplitude_um - 3.0) < 0.03
    # the refined peak is the maximum of the least-squares amplitude nearby
    f = 1 / sp.peak_period_mm
    around = sine_amplitude_um(x, y, f + np.linspace(-1e-4, 1e-4, 41))
    assert sp.peak_amplitude_um >= around.max() - 1e-9
