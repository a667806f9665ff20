"""Is a figure resolved by the data? One rule for the report, the GUI and the verdicts.

A figure is *resolved* when its uncertainty is below both its value and the
limit it is judged against; otherwise it is shown as "not resolved (sigma X)"
and never as a finding. For a peak-to-valley (or a maximum of |x|) over many
views the uncertainty that matters is what noise alone would produce: the
expected range of n independent normal errors, which grows like
2 sigma sqrt(2 ln n) (about 6 sigma for 400 views), so a p-v is resolved only
when it clearly exceeds that noise p-v.

ISO 230-2 asks for 5 runs per direction; verdicts from fewer are indicative.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ndtri

ISO_RUNS_PER_DIRECTION = 5


def expected_max_normal(n: int) -> float:
    """E[max of n standard normals], Blom's approximation (within 1 % for n >= 5)."""
    if n < 2:
        return 0.0
    return float(ndtri((n - 0.375) / (n + 0.25)))


def noise_peak_to_valley(sigma: float, n: int) -> float:
    """Expected peak-to-valley of n independent N(0, sigma^2) values."""
    return 2.0 * float(sigma) * expected_max_normal(int(n))


def noise_max_abs(sigma: float, n: int) -> float:
    """Expected max |x| of n independent N(0, sigma^2) values."""
    if n < 1:
        return 0.0
    p = (n - 0.375) / (n + 0.25)
    return float(sigma) * float(ndtri(0.5 * (1.0 + p)))


def is_resolved(value: float | None, sigma: float | None, limit: float | None = None) -> bool:
    """True when ``sigma`` is finite and below |value| and below ``limit`` (if given)."""
    if value is None or sigma is None or not (math.isfinite(value) and math.isfinite(sigma)):
        return False
    if sigma >= abs(value):
        return False
    return limit is None or sigma < limit


def not_resolved_text(sigma: float | None, unit: str, digits: int = 2) -> str:
    """``"not resolved (σ 12 µm)"``: the words every reader of an unresolved figure sees."""
    if sigma is None or not math.isfinite(sigma):
        return "not resolved"
    return f"not resolved (\u03c3 {_short(sigma, digits)} {unit})"


def _short(v: float, digits: int) -> str:
    if v == 0:
        return "0"
    decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(v)))))
    return f"{v:.{decimals}f}"


@dataclass(frozen=True)
class ProfileSpan:
    """Peak-to-valley of an error profile over the targets, with what noise alone would give."""

    span: float | None  # p-v of the per-target means
    sigma: float | None  # median sigma of one per-target mean
    noise_span: float | None  # expected p-v from noise alone (the p-v's uncertainty)
    n_targets: int
    resolved: bool

    def to_dict(self, unit: str) -> dict[str, Any]:
        return {f"span_{unit}": self.span, f"sigma_{unit}": self.sigma, f"noise_span_{unit}": self.noise_span,
                "n_targets": self.n_targets, "resolved": self.resolved}


def profile_span(values: np.ndarray, sigma: np.ndarray, target: np.ndarray, valid: np.ndarray,
                 limit: float | None = None) -> ProfileSpan:
    """P-v of the per-target means of ``values`` (all runs and directions averaged).

    Averaging the captures of one target divides their independent noise by
    sqrt(n); the p-v is then judged against the noise p-v of that many targets.
    """
    v = np.asarray(values, float)
    s = np.asarray(sigma, float)
    ok = np.asarray(valid, bool) & np.isfinite(v) & np.isfinite(s)
    if ok.sum() < 2:
        return ProfileSpan(None, None, None, 0, False)
    keys, inv = np.unique(np.round(np.asarray(target, float)[ok], 6), return_inverse=True)
    m = keys.size
    count = np.bincount(inv, minlength=m)
    mean = np.bincount(inv, weights=v[ok], minlength=m) / count
    sig_mean = np.sqrt(np.bincount(inv, weights=s[ok] ** 2, minlength=m)) / count
    span = float(np.ptp(mean))
    sig = float(np.median(sig_mean))
    noise = noise_peak_to_valley(float(np.sqrt(np.mean(sig_mean**2))), m)
    return ProfileSpan(span, sig, noise, int(m), is_resolved(span, noise, limit))


def runs_per_direction(figures: dict[str, Any]) -> int:
    """The smaller number of runs of the directions measured (from ``figures["per_run"]``)."""
    counts: dict[str, int] = {}
    for r in figures.get("per_run") or []:
        counts[str(r.get("direction"))] = counts.get(str(r.get("direction")), 0) + 1
    return min(counts.values()) if counts else 0


def is_indicative(figures: dict[str, Any]) -> bool:
    """True when fewer runs per direction than ISO 230-2 asks back the figures."""
    return runs_per_direction(figures) < ISO_RUNS_PER_DIRECTION
