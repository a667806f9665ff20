"""Figures that are an extreme over noisy values (max |x|, a p-v span), with the noise's selection taken out.

Why (issue 35): a max over noisy values picks the largest draws near the peak,
so it comes out above the true extreme by about the noise's own expected
maximum there, and U = k times one value's sigma holds neither that bias nor
the max's spread: max |roll| over 48 per-view poses (sigma ~400 urad) was
+752 urad off on U 834 (covered 50 %), a row's EBX p-v covered 20 %. The
ISO 230-2 figures had the same fault and :mod:`.iso230_noise` takes it out.

How: the SIMEX the ISO 230-2 figures use (:func:`simex_curve`, here, the one
implementation: :mod:`.iso230_noise` imports it): the extreme's mean under
fresh draws of lambda times the values' noise covariance (independent sigmas,
or a factor of a correlated covariance), extrapolated to no noise at all. The
extrapolant is the question: where the truth dominates, the extreme's
inflation grows with the noise's variance (a quadratic in lambda, to lambda =
-1, is exact); where the noise dominates it is the noise's own max, linear in
its sd (a line in sqrt(1 + lambda), to 0, is exact). The one falls short, the
other overshoots (synthetic profiles of 12-60 values at 0.5-30 sigma: +0.4 to
+1.8 sigma and -0.2 to -1.1 sigma). The corrected figure is their midpoint, its
noise standard uncertainty ``SIMEX_U_FACTOR`` times the spread at lambda = 1
and the half-difference as a uniform term (on those profiles: bias within
+-0.7 sigma, coverage of k = 2 93-99 %, mean z^2 0.6-1.0). Terms common to every
value (a scale, the intrinsics) are the caller's budget, not noise here.

Pure numpy, a fixed seed: the same data give the same figures.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ExtremeFigure", "corrected_extreme", "simex"]

SIMEX_LAMBDA = (0.5, 1.0, 1.5, 2.0)  # added noise variance in units of the views' own
SEED = 20260535
# the extrapolated figure scatters more than the measured one: over 60 synthetic sessions (12 targets, 2 runs each
# way, noise 1-3 um on repeatability 1-3 um) its error's sd was 1.37-1.62 times the sd at lambda = 1
SIMEX_U_FACTOR = 1.5

DRAWS = 400  # Monte Carlo draws: 100 per lambda


def _max_abs(x: np.ndarray) -> np.ndarray:
    return np.array([np.max(np.abs(x))])


def _span(x: np.ndarray) -> np.ndarray:
    return np.array([np.ptp(x)])


def simex_curve(figure: Callable[[np.ndarray], np.ndarray], x: np.ndarray, noise: np.ndarray, draws: int = DRAWS,
                squared: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The figures' mean against the added noise variance: (lambda (L,) from 0, means (L, F), sd at lambda = 1).

    ``figure`` maps the values (K,) to figures (F,); ``noise`` (K,) is each value's own noise (1 sigma),
    or (K, r) a factor L of correlated noise (covariance L L^T: per-target means that share a reference).
    lambda = 0 is the measured figure itself; each other lambda the mean over fresh draws of lambda sigma^2.
    ``squared``: the means are of each figure's signed square (the sd stays the figure's own).
    """
    measured = figure(x)
    lam = np.array((0.0,) + SIMEX_LAMBDA)
    if not np.isfinite(measured).any():
        return lam, np.full((lam.size, measured.size), np.nan), np.full_like(measured, np.nan)
    rng = np.random.default_rng(SEED)
    per = max(draws // len(SIMEX_LAMBDA), 2)
    means, sd = [_signed_square(measured) if squared else measured], np.full_like(measured, np.nan)
    for a in SIMEX_LAMBDA:
        sims = np.array([figure(x + np.sqrt(a) * _draw(noise, rng)) for _ in range(per)])
        means.append((_signed_square(sims) if squared else sims).mean(axis=0))  # undefined figures: NaN in every draw
        if a == 1.0:
            sd = sims.std(axis=0, ddof=1)
    return lam, np.vstack(means), sd


def simex(figure: Callable[[np.ndarray], np.ndarray], x: np.ndarray, noise: np.ndarray, draws: int = DRAWS,
          squared: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """SIMEX of a vector of figures of ``x``: (measured, the noise's bias, the figures' sd at lambda = 1).

    :func:`simex_curve`'s means as a quadratic in the added noise variance, extrapolated to lambda = -1 (no
    noise at all). ``squared``: the signed square of each figure is taken as linear in lambda instead and the
    root of its extrapolation returned (a planar axis's worst line, :func:`.iso230_noise.noise_corrected_worst`).
    """
    lam, means, sd = simex_curve(figure, x, noise, draws, squared)
    measured = figure(x) if squared else means[0]
    if not np.isfinite(measured).any():
        return measured, np.full_like(measured, np.nan), sd
    extrapolated = np.polyval(np.polyfit(lam, np.nan_to_num(means), 1 if squared else 2), -1.0)
    if squared:
        extrapolated = np.sign(extrapolated) * np.sqrt(np.abs(extrapolated))
    return measured, measured - extrapolated, sd


def _signed_square(x: np.ndarray) -> np.ndarray:
    return np.sign(x) * x**2


def _draw(noise: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One draw of the noise: independent (``noise`` (K,) sigmas) or correlated (``noise`` (K, r) a factor)."""
    if noise.ndim == 2:
        return noise @ rng.standard_normal(noise.shape[1])
    return noise * rng.standard_normal(noise.size)


KINDS: dict[str, Callable[[np.ndarray], np.ndarray]] = {"max_abs": _max_abs, "span": _span}


@dataclass(frozen=True)
class ExtremeFigure:
    """An extreme's measured value, the noise's bias, the corrected value and its noise standard uncertainty."""

    measured: float
    bias: float
    u_noise: float
    corrected: float

    def to_dict(self) -> dict[str, Any]:
        return {"measured": self.measured, "bias": self.bias, "u_noise": self.u_noise, "corrected": self.corrected}


def corrected_extreme(values: np.ndarray, noise: np.ndarray, kind: str = "max_abs",
                      draws: int = DRAWS) -> ExtremeFigure | None:
    """The ``kind`` extreme ("max_abs" or "span") of the finite ``values``, the noise's selection taken out.

    ``noise``: (n,) each value's independent sigma, or (n, r) a factor L of their covariance L L^T (same unit as
    the values). None when fewer than two values are finite. ``corrected`` is never below 0 (both kinds are
    magnitudes); ``u_noise`` is 1 sigma.
    """
    v = np.asarray(values, float)
    f = np.asarray(noise, float)
    keep = np.isfinite(v) & (np.all(np.isfinite(f), axis=1) if f.ndim == 2 else np.isfinite(f))
    if keep.sum() < 2:
        return None
    lam, means, sd = simex_curve(KINDS[kind], v[keep], f[keep], draws)
    m, s = float(means[0, 0]), float(sd[0])
    if not (np.isfinite(means).all() and math.isfinite(s)):
        return ExtremeFigure(m, 0.0, 0.0, m)
    in_variance = float(np.polyval(np.polyfit(lam, means[:, 0], 2), -1.0))  # exact where the truth dominates
    in_sd = float(np.polyval(np.polyfit(np.sqrt(1.0 + lam), means[:, 0], 1), 0.0))  # exact where the noise does
    half = 0.5 * abs(in_variance - in_sd)
    bias = m - 0.5 * (in_variance + in_sd)
    return ExtremeFigure(m, bias, float(math.hypot(SIMEX_U_FACTOR * s, half / math.sqrt(3.0))), max(m - bias, 0.0))
