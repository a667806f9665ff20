"""Periodic positioning error (SPEC section 5): spectrum of detrended deviations.

A lead screw repeats its error every turn, so the deviation of a stage from
its scale line carries a sine at the screw pitch. On a uniform target grid we
take the FFT; on any other grid (missing targets, outliers left out, several
runs pooled) the generalized Lomb-Scargle periodogram, which is the weighted
least-squares sine fit with a floating mean at each frequency (batched 3x3
normal equations in numpy; the same numbers as scipy.signal.lombscargle, whose
import alone costs more than a whole small estimate). The peak is then refined
by zooming a grid of that least-squares fit, so its amplitude does not suffer
the FFT's scalloping loss when the pitch falls between bins.

A period is only a figure where the plan defines it (:func:`resolvable_band`):
at least MIN_CYCLES of it in the travel, MIN_SAMPLES_PER_PERIOD samples in
one period and no gap wider than half of it. Near the Nyquist period the sine
column of the fit vanishes and the "amplitude" is noise divided by almost zero
(3.45e+15 um on a 0-10 mm plan at 2 mm steps); on a min-step plan's clusters
every period aliases. There the peak is None: "not defined". Pure math, no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

OVERSAMPLE = 2  # Lomb-Scargle frequency step = 1 / (OVERSAMPLE * travel); the peak is refined anyway
MAX_FFT_WEIGHT_RATIO = 4.0  # a uniform grid with weights within this ratio takes the FFT
MAX_FREQUENCIES = 4096  # cap on the Lomb-Scargle grid (cost O(K * F))
MIN_CYCLES = 2.0  # the peak must repeat at least this often within the travel
MIN_SAMPLES_PER_PERIOD = 4.0  # the peak's period holds at least this many typical steps (twice the Nyquist limit)
UNDEFINED_TEXT = "not defined (the plan resolves no period)"  # the words a reader sees instead of a value
UNDEFINED_NOTE = (f"Periodic error not defined: a period needs {MIN_CYCLES:g} cycles in the travel, "
                  f"{MIN_SAMPLES_PER_PERIOD:g} samples in a cycle and no gap over half a cycle.")
ZOOM_POINTS = 17  # frequencies per zoom step of the peak refinement
ZOOM_TOL = 1e-6  # refine the peak frequency to this fraction of 1/travel
LS_BLOCK = 1 << 20  # frequencies x samples evaluated at once (memory cap)


@dataclass
class Spectrum:
    """Amplitude spectrum of the detrended deviation and its peak."""

    period_mm: np.ndarray  # shape (F,), descending (ascending frequency)
    amplitude_um: np.ndarray  # shape (F,), sine amplitude at each period
    method: str  # "fft" (uniform grid) or "lomb-scargle"
    peak_period_mm: float | None  # refined period of the largest peak in the resolvable band; None: none
    peak_amplitude_um: float | None  # least-squares sine amplitude at that period

    def to_dict(self) -> dict[str, Any]:
        """The arrays for plotting (results.json ``spectrum``); the peak is reported by the caller."""
        return {"period_mm": [float(p) for p in self.period_mm],
                "amplitude_um": [float(a) for a in self.amplitude_um], "method": self.method}


def sine_amplitude_um(x_mm: np.ndarray, y_um: np.ndarray, freq_per_mm: np.ndarray,
                      weights: np.ndarray | None = None) -> np.ndarray:
    """Least-squares sine amplitude of y at each frequency (cycles/mm), with a floating mean; shape (F,)."""
    x = np.asarray(x_mm, float)
    y = np.asarray(y_um, float)
    w = np.ones_like(x) if weights is None else np.asarray(weights, float)
    w = w / w.sum()
    omega = np.atleast_1d(np.asarray(freq_per_mm, dtype=float)) * 2.0 * np.pi
    out = np.empty(omega.shape)
    block = max(1, LS_BLOCK // max(1, x.size))
    for lo in range(0, omega.size, block):
        phase = omega[lo : lo + block, None] * x  # shape (F, K)
        c, s = np.cos(phase), np.sin(phase)
        wc, ws = c * w, s * w
        A = np.empty((len(phase), 3, 3))
        A[:, 0, 0] = np.einsum("fk,fk->f", wc, c)
        A[:, 0, 1] = A[:, 1, 0] = np.einsum("fk,fk->f", wc, s)
        A[:, 1, 1] = np.einsum("fk,fk->f", ws, s)
        A[:, 0, 2] = A[:, 2, 0] = wc.sum(axis=1)
        A[:, 1, 2] = A[:, 2, 1] = ws.sum(axis=1)
        A[:, 2, 2] = 1.0
        b = np.stack([wc @ y, ws @ y, np.full(len(phase), w @ y)], axis=1)
        coef = np.linalg.solve(A, b[..., None])[..., 0]
        out[lo : lo + block] = np.hypot(coef[:, 0], coef[:, 1])
    return out


def _refine_peak(xs: np.ndarray, ys: np.ndarray, ws: np.ndarray, lo: float, hi: float, tol: float) -> tuple[float, float]:
    """Frequency and amplitude of the largest least-squares sine in [lo, hi], by zooming a grid."""
    while True:
        f = np.linspace(lo, hi, ZOOM_POINTS)
        a = sine_amplitude_um(xs, ys, f, ws)
        j = int(np.argmax(a))
        step = f[1] - f[0]
        if step <= tol:
            return float(f[j]), float(a[j])
        lo, hi = max(lo, f[j] - step), min(hi, f[j] + step)


def _uniform(x_sorted: np.ndarray, weights: np.ndarray) -> float | None:
    """The grid step (mm) if x is equally spaced and the weights nearly equal, else None.

    Weights within a factor MAX_FFT_WEIGHT_RATIO (sigmas within a factor 2) change
    a sine's amplitude negligibly, so such a grid takes the (unweighted) FFT.
    """
    d = np.diff(x_sorted)
    if np.max(weights) > MAX_FFT_WEIGHT_RATIO * np.min(weights):
        return None
    step = float(np.median(d))
    if step <= 0 or np.max(np.abs(d - step)) > 1e-6 * step:
        return None
    return step


def _collapse_repeats(x_mm: np.ndarray, y_um: np.ndarray, weights: np.ndarray | None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weighted mean of y at each distinct x (within 1e-6 mm), ascending; weights summed.

    A least-squares sine fit to repeats equals the fit to their weighted means
    with summed weights, so pooled runs cost no more than one run.
    """
    w = np.ones(np.shape(x_mm)) if weights is None else np.asarray(weights, float)
    key = np.round(np.asarray(x_mm, float) / 1e-6).astype(np.int64)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    inv = inv.ravel()
    w_sum = np.bincount(inv, w)
    return np.asarray(x_mm, float)[first], np.bincount(inv, w * np.asarray(y_um, float)) / w_sum, w_sum


def top_frequency(x_sorted: np.ndarray) -> float:
    """The highest frequency (cycles/mm) the distinct positions ``x_sorted`` resolve.

    MIN_SAMPLES_PER_PERIOD typical (median) steps in a period, and the largest
    gap at most half a period, so that no period aliases through a hole in
    the plan. 0 with fewer than two distinct positions.
    """
    gaps = np.diff(x_sorted)
    if gaps.size == 0 or not gaps.max() > 0:
        return 0.0
    return min(1.0 / (MIN_SAMPLES_PER_PERIOD * float(np.median(gaps))), 0.5 / float(gaps.max()))


def resolvable_band(x_sorted: np.ndarray) -> tuple[float, float] | None:
    """The frequencies (cycles/mm) whose sine the distinct positions ``x_sorted`` define, or None:
    up to :func:`top_frequency`, with at least MIN_CYCLES periods in the travel."""
    if x_sorted.size < 4:
        return None
    f_lo, f_hi = MIN_CYCLES / float(x_sorted[-1] - x_sorted[0]), top_frequency(x_sorted)
    return (f_lo, f_hi) if f_hi >= f_lo * (1 - 1e-9) else None


def deviation_spectrum(x_mm: np.ndarray, y_um: np.ndarray, weights: np.ndarray | None = None) -> Spectrum | None:
    """Amplitude spectrum of detrended deviations ``y_um`` (shape (K,)) at positions ``x_mm``.

    Repeated positions are merged into their weighted mean first. ``weights``
    (1/sigma^2, shape (K,)) weight the Lomb-Scargle fit; a uniform grid with
    nearly equal weights takes the FFT, any other the Lomb-Scargle periodogram.
    Returns None with fewer than 4 distinct positions. The spectrum stops at
    the highest frequency the positions resolve (:func:`top_frequency`); the
    peak is None when they resolve no period (:func:`resolvable_band`).
    """
    xs, ys, ws = _collapse_repeats(x_mm, y_um, weights)
    if xs.size < 4:
        return None
    travel_mm = float(xs[-1] - xs[0])
    step = _uniform(xs, ws)
    if step is not None:
        n = xs.size
        k = np.arange(1, n // 2 + 1)
        amp = 2.0 * np.abs(np.fft.rfft(ys - ys.mean())[k]) / n
        if n % 2 == 0:
            amp[-1] /= 2.0  # the Nyquist bin is real: no factor 2
        freq = k / (n * step)
        method = "fft"
    else:
        # Stop 1/travel short of the grid's Nyquist frequency: on a gappy regular grid the sine
        # column of the fit vanishes there and its amplitude is noise divided by almost zero.
        f_lo = 1.0 / travel_mm
        f_hi = min(0.5 / float(np.median(np.diff(xs))) - 1.0 / travel_mm, top_frequency(xs))
        nf = int(min(MAX_FREQUENCIES, max(2, np.floor((f_hi - f_lo) * OVERSAMPLE * travel_mm) + 1)))
        freq = np.linspace(f_lo, f_hi, nf) if f_hi >= f_lo else np.empty(0)
        amp = sine_amplitude_um(xs, ys, freq, ws)
        method = "lomb-scargle"
    shown = freq <= top_frequency(xs) * (1 + 1e-9)  # beyond it a "period" is an alias of the plan
    freq, amp = freq[shown], amp[shown]
    band = resolvable_band(xs)
    if band is None:
        return Spectrum(1.0 / freq, amp, method, None, None)
    inside = (freq >= band[0] * (1 - 1e-9)) & (freq <= band[1] * (1 + 1e-9))
    lo, hi = band
    if inside.any():
        i = int(np.argmax(np.where(inside, amp, -np.inf)))
        lo, hi = max(freq[i] - 1.0 / travel_mm, band[0]), min(freq[i] + 1.0 / travel_mm, band[1])
    f_best, a_best = _refine_peak(xs, ys, ws, lo, hi, ZOOM_TOL / travel_mm)
    if inside.any() and amp[i] > a_best:
        f_best, a_best = float(freq[i]), float(amp[i])
    return Spectrum(1.0 / freq, amp, method, 1.0 / f_best, a_best)
