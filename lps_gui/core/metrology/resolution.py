"""Is a figure resolved by the data? One rule for the report, the GUI and the verdicts.

A figure is *resolved* when its uncertainty is below both its value and the
limit it is judged against; otherwise it is shown as "not resolved (sigma X)"
and never as a finding. For a peak-to-valley (or a maximum of |x|) over many
views the uncertainty that matters is what noise alone would produce: the
range of n independent normal errors has mean ~2 sigma sqrt(2 ln n) (about
6 sigma for 400 views) and a spread of its own, so the "noise p-v" is its
mean plus 3 standard deviations, and a p-v is resolved only above it.

The value printed for a p-v or a max |x| is the extreme with the noise's selection taken out
(:mod:`lps_gui.core.metrology.extreme_noise`: the max of noisy values exceeds the true max), with that
correction's standard uncertainty; it is a finding only when it also exceeds its own U (k = 2).

ISO 230-2 asks for 5 runs per direction; verdicts from fewer are indicative.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.metrology.extreme_noise import corrected_extreme


def chi2_sf(x: float, dof: float) -> float:
    """Survival function of chi-square, P(X > x) (scipy.special's: scipy.stats is far slower to import).

    scipy.special (itself slow to import) is imported here, where it is used, not
    by everything that imports this module (`lps estimate` reads its inputs first).
    """
    from scipy.special import chdtrc

    return float(chdtrc(dof, x))


def _ndtri(p: float) -> float:
    """The standard normal quantile (scipy.special's, imported when first needed)."""
    from scipy.special import ndtri

    return float(ndtri(p))


ISO_RUNS_PER_DIRECTION = 5
NOISE_K = 3.0  # a p-v is a finding only when 3 sd above what noise alone gives
PROFILE_P_VALUE = 1e-3  # ... and its profile is not flat at this significance
NOISE_DRAWS = 400  # draws of correlated noise whose p-v give the noise p-v (no closed form)
U_K = 2.0  # the coverage factor of the U a corrected extreme must exceed to be a finding


def expected_max_normal(n: int) -> float:
    """E[max of n standard normals], Blom's approximation (within 1 % for n >= 5)."""
    if n < 2:
        return 0.0
    return _ndtri((n - 0.375) / (n + 0.25))


def _sd_max_normal(n: int) -> float:
    """Standard deviation of the max of n standard normals (Gumbel limit, ~10 % for n >= 10)."""
    if n < 2:
        return 1.0
    return float(math.pi / math.sqrt(6.0) / math.sqrt(2.0 * math.log(n)))


def noise_peak_to_valley(sigma: float, n: int, k: float = NOISE_K) -> float:
    """The p-v that n independent N(0, sigma^2) values stay below: mean + k sd of their range."""
    return float(sigma) * (2.0 * expected_max_normal(int(n)) + k * math.sqrt(2.0) * _sd_max_normal(int(n)))


def noise_max_abs(sigma: float, n: int, k: float = NOISE_K) -> float:
    """The max |x| that n independent N(0, sigma^2) values stay below: mean + k sd."""
    if n < 1:
        return 0.0
    p = (n - 0.375) / (n + 0.25)
    return float(sigma) * (_ndtri(0.5 * (1.0 + p)) + k * _sd_max_normal(2 * int(n)))


def is_resolved(value: float | None, sigma: float | None, limit: float | None = None) -> bool:
    """True when ``sigma`` is finite and below |value| and below ``limit`` (if given)."""
    if value is None or sigma is None or not (math.isfinite(value) and math.isfinite(sigma)):
        return False
    if sigma >= abs(value):
        return False
    return limit is None or sigma < limit


def not_resolved_text(bound: float | None, unit: str, digits: int = 2, what: str = "noise p-v") -> str:
    """``"not resolved (noise p-v 12 µm)"``: the words every reader of an unresolved figure sees.

    ``bound`` is what noise alone reaches (:func:`noise_peak_to_valley`, or
    :func:`noise_max_abs` with ``what="noise max"``), not a 1-sigma: it is
    named as such, the same words page 1's verdict notes use.
    """
    if bound is None or not math.isfinite(bound):
        return "not resolved"
    return f"not resolved ({what} {_short(bound, digits)} {unit})"


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
    measured_span: float | None = None  # p-v of the measured means, before the noise's selection is taken out
    u_span: float | None = None  # standard uncertainty of ``span`` from the means' noise (:mod:`.extreme_noise`)

    def to_dict(self, unit: str) -> dict[str, Any]:
        return {f"span_{unit}": self.span, f"sigma_{unit}": self.sigma, f"noise_span_{unit}": self.noise_span,
                "n_targets": self.n_targets, "resolved": self.resolved, f"measured_span_{unit}": self.measured_span,
                f"u_span_{unit}": self.u_span}


def _correlated_noise(mean: np.ndarray, cov: np.ndarray) -> tuple[float, int, float]:
    """Chi-square of ``mean`` against its full covariance (its constant taken out), its dof, and the noise p-v.

    Generalized: (P v)^T (P C P)^+ (P v) with P removing the mean (the gauge: every profile is relative to a
    reference) and the rank of P C P as the dof; the noise p-v is mean + NOISE_K sd of the p-v of
    NOISE_DRAWS seeded draws of N(0, C) (deterministic; the range of correlated noise has no closed form).
    """
    m = mean.size
    P = np.eye(m) - 1.0 / m
    lam, U = np.linalg.eigh(P @ cov @ P)
    keep = lam > max(float(lam[-1]), 0.0) * 1e-9
    if not keep.any():
        return 0.0, 0, 0.0
    lam, U = lam[keep], U[:, keep]
    chi2 = float(np.sum((U.T @ (P @ mean)) ** 2 / lam))
    draws = (np.random.default_rng(0).standard_normal((NOISE_DRAWS, lam.size)) * np.sqrt(lam)) @ U.T
    spans = np.ptp(draws, axis=1)
    return chi2, int(lam.size), float(spans.mean() + NOISE_K * spans.std(ddof=1))


def difference_noise(mean: np.ndarray, order: int = 2) -> float:
    """The scatter of equally spaced per-target means that is not the profile: sqrt(mean(d_k^2) / C(2k, k)),
    d_k their k-th differences, k = min(``order``, m - 3) (at least three differences).

    White noise's k-th differences have variance C(2k, k) sigma^2 at any k, but a profile's own curvature
    passes second differences (a 1.1 mm roll bow over 12 targets read as 28 um of noise per mean, 30x the
    corners' 0.9 um, on the honesty campaign's ``motions`` stage) and cancels in the fourth (any cubic).
    Order 2 stays the default: on the error motions (an angle per stop) that floor also stands for errors
    that are not noise (a stop's tilt-perspective trade-off); order 4 is for a board-plane straightness,
    whose U names its one systematic term (pipeline/results/board_plane.py).
    """
    m = int(np.asarray(mean).size)
    k = min(int(order), m - 3)
    if k < 2:
        return 0.0
    return float(np.sqrt(np.mean(np.diff(np.asarray(mean, float), k) ** 2) / math.comb(2 * k, k)))


def per_target_means(values: np.ndarray, sigma: np.ndarray, target: np.ndarray, difference_order: int = 2
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(index of each value's target, views per target, per-target means, their sigmas), targets sorted.

    The views of a target are averaged (their independent noise divided by sqrt(n)); a mean's sigma is at
    least the scatter seen in the data (:func:`difference_noise` of ``difference_order``, five targets or more;
    none below order 2), for an error that repeats at the same pose. Used by :func:`profile_span` and
    :func:`max_abs_resolution`.
    """
    keys, inv = np.unique(np.round(np.asarray(target, float), 6), return_inverse=True)
    count = np.bincount(inv, minlength=keys.size)
    mean = np.bincount(inv, weights=values, minlength=keys.size) / count
    sig_mean = np.sqrt(np.bincount(inv, weights=sigma**2, minlength=keys.size)) / count
    if keys.size >= 5:  # noise seen in the data: differences of neighbouring targets (keys are sorted)
        sig_mean = np.maximum(sig_mean, difference_noise(mean, difference_order))
    return inv, count, mean, sig_mean


def centred_target_means(values: np.ndarray, sigma: np.ndarray, target: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """The per-target means of an angle about their mean, and a factor L (m, m) of their noise (C = L L^T).

    Why (issue 35): a camera cannot see a stage's nominal attitude (the board's mount is unknown), so an
    angle's zero is an estimate: the line model's common orientation, which on the campaign's motions stage sat
    ~245 urad off the roll profile's mean in every seed (a max |roll| error no term of U named; a p-v does not
    see it). The stops' mean attitude is observed: max |angle| is taken about it, in the estimate and in the
    truth (sim/truth_figures.py). No difference floor (:func:`max_abs_resolution`).
    """
    _, _, mean, sig_mean = per_target_means(values, sigma, target, difference_order=0)
    centring = np.eye(mean.size) - 1.0 / mean.size
    return mean - mean.mean(), centring * sig_mean[None, :]


def profile_span(values: np.ndarray, sigma: np.ndarray, target: np.ndarray, valid: np.ndarray,
                 limit: float | None = None, covariance: np.ndarray | None = None,
                 difference_order: int = 2) -> ProfileSpan:
    """P-v of the per-target means of ``values`` (all runs and directions averaged).

    Averaging the captures of one target divides their independent noise by
    sqrt(n), but not an error that repeats at the same pose (a corner
    detector's bias on a rendered or real image): the sigma of a per-target
    mean is therefore at least the scatter seen in the data, from
    differences of neighbouring targets (:func:`difference_noise`: a smooth profile has none). Resolved: the per-target means differ from zero (they are already
    off a least-squares line) at p < 0.001 by a chi-square test, and the p-v
    exceeds the noise p-v of that many targets (and the limit, if given).

    ``covariance`` (n, n), of ``values``: when the values' errors are correlated (the angles of a
    constellation's stops share the targets' relative poses, which chain along the row), the
    independent test understates what noise alone produces; with it both the chi-square and the
    noise p-v come from the per-target means' full covariance (:func:`_correlated_noise`).
    ``difference_order``: of the differences the floor is taken from (:func:`difference_noise`).
    """
    v = np.asarray(values, float)
    s = np.asarray(sigma, float)
    ok = np.asarray(valid, bool) & np.isfinite(v) & np.isfinite(s)
    if ok.sum() < 2:
        return ProfileSpan(None, None, None, 0, False)
    inv, count, mean, sig_mean = per_target_means(v[ok], s[ok], np.asarray(target, float)[ok], difference_order)
    m = mean.size
    measured = float(np.ptp(mean))
    sig = float(np.median(sig_mean))
    factor: np.ndarray = sig_mean
    if covariance is None:
        noise = noise_peak_to_valley(float(np.sqrt(np.mean(sig_mean**2))), m)
        # a profile is a finding when it is significantly not flat (chi-square of the per-target means
        # against their sigma, two dof taken by the reference line), not merely when its range is large
        chi2 = float(np.sum((mean / np.maximum(sig_mean, 1e-300)) ** 2))
        dof = m - 2
    else:
        avg = np.zeros((m, inv.size))
        avg[inv, np.arange(inv.size)] = 1.0 / count[inv]
        idx = np.flatnonzero(ok)
        cov = avg @ np.asarray(covariance, float)[np.ix_(idx, idx)] @ avg.T
        centred_var = np.diag(cov) - 2.0 * cov.mean(axis=1) + cov.mean()  # of mean_i - mean over the targets
        # the scatter seen in the data beyond the covariance's (sig_mean's floor above): independent per target
        cov = cov + np.diag(np.maximum(sig_mean**2 - centred_var, 0.0))
        chi2, dof, noise = _correlated_noise(mean, cov)
        lam, vec = np.linalg.eigh(0.5 * (cov + cov.T))
        factor = vec * np.sqrt(np.clip(lam, 0.0, None))
    significant = m > 2 and dof > 0 and float(chi2_sf(chi2, dof)) < PROFILE_P_VALUE
    ext = corrected_extreme(mean, factor, "span")
    span, u = (measured, None) if ext is None else (ext.corrected, ext.u_noise)
    resolved = significant and is_resolved(measured, noise, limit) and (u is None or span > U_K * u)
    return ProfileSpan(span, sig, noise, int(m), resolved, measured, u)


def max_abs_resolution(values: np.ndarray, sigma: np.ndarray, target: np.ndarray, valid: np.ndarray,
                       profile: ProfileSpan | None = None) -> dict[str, Any] | None:
    """Max |x| of a profile's targets' means about their mean (an angle: "Max |roll|") and whether it is a finding.

    The one rule for a max |x|: it is a finding only when it exceeds what noise
    alone reaches (:func:`noise_max_abs` of the means' RMS sigma) *and* the
    profile it comes from is resolved (:func:`profile_span`: not flat at
    p < 0.001, p-v above the noise p-v), and the value printed (the noise's selection taken out,
    :func:`~lps_gui.core.metrology.extreme_noise.corrected_extreme`) exceeds its own U (k = 2):
    ``max_abs_urad`` is that value, ``measured_max_abs_urad`` the raw max, ``u_max_abs_urad`` its
    standard uncertainty. ``profile`` is that profile when the
    caller has a better one (the error motions' own, with the stops' full
    covariance: then the summary's "Max |roll|" and the error-motion table
    cannot disagree); otherwise it is computed from ``values`` and ``sigma``
    as independent. None when no view has a value.
    """
    v, s = np.asarray(values, float), np.asarray(sigma, float)
    keep = np.asarray(valid, bool) & np.isfinite(v) & np.isfinite(s)
    if not keep.any():
        return None
    if profile is None:
        profile = profile_span(v, s, target, keep)
    # the angle at a place is the stage's, its views repeated measurements of it: the max over single views picked
    # the noise's largest draw (issue 35: max |pitch| on the campaign's motions stage, 300 urad a view on a
    # +-660 urad profile over 48 views, read 1.1-1.7 mrad; 83 % covered over 6 resolved line-both sessions, 75 %
    # over 4 of min-step, while EBX p-v, of the per-target means, passed): the max of those means, as the p-v's,
    # about their mean (:func:`centred_target_means`). No difference floor: a min-step's two places would read
    # their step as noise (resolved 1 of 10 with it, 5 without), and the stops' means of pitch are within their
    # sigma (z^2 0.97 on those sessions)
    centred, factor = centred_target_means(v[keep], s[keep], np.asarray(target, float)[keep])
    peak = float(np.max(np.abs(centred)))
    noise = noise_max_abs(float(np.sqrt(np.mean(np.sum(factor**2, axis=1)))), int(centred.size))
    ext = corrected_extreme(centred, factor, "max_abs")
    value, u = (peak, None) if ext is None else (ext.corrected, ext.u_noise)
    return {"max_abs_urad": value, "measured_max_abs_urad": peak, "u_max_abs_urad": u, "noise_max_abs_urad": noise,
            "resolved": bool(is_resolved(peak, noise) and profile.resolved and (u is None or value > U_K * u))}


def with_profile_resolution(angles: dict[str, Any], profile_resolved: dict[str, bool]) -> dict[str, Any]:
    """``figures["angles_resolution"]`` once the error motions have their profiles' verdicts
    (``{"roll": bool, ...}``): a max |angle| whose profile is not resolved is no finding
    (:func:`max_abs_resolution`'s rule, with the error motions' profile)."""
    return {name: {**entry, "resolved": bool(entry.get("resolved")) and profile_resolved.get(name, True)}
            for name, entry in angles.items()}


def runs_per_direction(figures: dict[str, Any]) -> int:
    """The smaller number of runs of the directions measured (from ``figures["per_run"]``)."""
    counts: dict[str, int] = {}
    for r in figures.get("per_run") or []:
        counts[str(r.get("direction"))] = counts.get(str(r.get("direction")), 0) + 1
    return min(counts.values()) if counts else 0


def is_indicative(figures: dict[str, Any]) -> bool:
    """True when fewer runs per direction than ISO 230-2 asks back the figures."""
    return runs_per_direction(figures) < ISO_RUNS_PER_DIRECTION


def straightness_verdict(figures: dict[str, Any], limit: float) -> dict[str, Any] | None:
    """Straight-line accuracy against ``limit`` (full width) from the resolved v1/v2 spans, or None.

    Uses ``figures["straightness"]`` (per-target p-v of each direction with its
    noise p-v). Noise only inflates a p-v, so p-v <= limit passes; a p-v above
    the limit by more than its noise p-v fails; in between, or when the noise
    p-v alone reaches the limit, the limit is not resolved (``passed`` None).
    A span flat within noise still passes: the data resolve that it is below.
    A resolved failure in one direction fails even if the other is not resolved.
    """
    st = figures.get("straightness")
    if not isinstance(st, dict) or not all(isinstance(st.get(k), dict) for k in ("v1", "v2")):
        return None
    verdicts, notes, spans = [], [], []
    for k in ("v1", "v2"):
        span, noise = st[k].get("span_um"), st[k].get("noise_span_um")
        if span is None or noise is None:
            verdicts.append(None)
            notes.append(f"{k} not measured")
            continue
        spans.append(float(span))
        head = f"{k} {_short(span, 3)} \u00b5m (noise p-v {_short(noise, 2)}{'' if st[k].get('resolved') else ', flat within noise'})"
        if span - noise > limit:
            verdicts.append(False)
            notes.append(f"{head} above the limit beyond its noise")
        elif noise >= limit:
            verdicts.append(None)
            notes.append(f"{k} not resolved: noise alone spans {_short(noise, 2)} \u00b5m")
        elif span <= limit:
            verdicts.append(True)
            notes.append(head)
        else:
            verdicts.append(None)
            notes.append(f"{head} within its noise of the limit")
    passed = False if False in verdicts else (True if all(v is True for v in verdicts) else None)
    m = st["v1"].get("n_targets")
    basis = str(st.get("basis", ""))
    return {"measured": max(spans) if spans else None, "passed": passed,
            "note": f"p-v over {m} targets at the {basis.split(',')[0] if basis else 'board plane'}: " + "; ".join(notes)}
