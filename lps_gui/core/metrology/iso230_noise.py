"""ISO 230-2 figures with the measurement noise taken out, and the noise's own uncertainty (issue 35).

Why: A, R, B, E and M are built from per-target means and standard
deviations of the *measured* deviations. The camera's per-view noise adds to
each approach independently: it adds to every s_j in quadrature
(s_meas^2 = s_true^2 + sigma^2) and the maximum over targets picks the worst
draw, so R and A come out larger than the stage's by several sigma (the first
campaign: A +7.5 um on U 7.6 um, R +11 um, coverage 50 %; 0 % with realism).
ISO 230-2's figures are the stage's, so the noise is the measurement's.

How: the figures are non-linear (max over targets of x̄ + 2s), so the noise is
propagated by Monte Carlo (GUM Supplement 1) and taken out by SIMEX (Cook and
Stefanski 1994, the simulation-extrapolation of measurement-error models):
the measured deviations plus fresh draws of lambda times each view's noise
variance give each figure's mean as a function of lambda (0.5 ... 2); a
quadratic through those means and the measured figure (lambda = 0),
extrapolated to lambda = -1, is the figure without noise. A one-step bootstrap
correction (lambda = 1 only) left half the bias: the inflation of sqrt(s^2 +
sigma^2) shrinks as s grows. The spread of the figure at lambda = 1, times
``SIMEX_U_FACTOR`` (the extrapolation scatters more), is the noise's standard
uncertainty of the corrected figure; it replaces the budget's per-displacement
noise rows in U (terms common to a target across runs - intrinsics, lens
misfit, print scale - stay in the budget). The reference view's noise is a
common offset of every deviation: no ISO figure (all differences) sees it.

Pure numpy, a fixed seed: the same data give the same figures.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from lps_gui.core.metrology.extreme_noise import SIMEX_U_FACTOR, corrected_extreme, simex
from lps_gui.core.metrology.iso230 import (ApproachPlan, approach_plan, bidirectional_figures, direction_signs,
                                           plan_figures)

__all__ = ["NOISE_KEYS", "apply_noise_correction", "independent_sigma_um", "noise_bound", "noise_corrected_iso",
           "noise_corrected_max_abs", "noise_corrected_worst", "simex"]

NOISE_KEYS = ("A_um", "A_up_um", "A_down_um", "E_um", "E_up_um", "E_down_um", "M_um",
              "R_um", "R_up_um", "R_down_um", "B_um", "B_mean_um")
DRAWS = 400  # Monte Carlo draws: the sd of a figure's noise to ~4 %
# a planar axis's worst line (noise_corrected_worst): u adds this share of the correction; on 40 synthetic draws each
# of the campaign's planar plan (3 and 5 lines, 2 runs, noise 1.9 and 7.9 um a view, the stage's A ~10 um) 0 left
# A covered in 78 % at the lower noise, 0.25 gave coverage 93-100 % and mean (error/sigma)^2 0.41-0.86 in all four
SELECTION_RESIDUAL = 0.25
REJECT_P = 0.001  # a claimed noise the run-to-run scatter rejects at this level is not the noise  # fixed: results do not change between runs of the same session


def independent_sigma_um(sigma_um: np.ndarray) -> np.ndarray:
    """Each view's own noise (um) from its sigma relative to the reference view.

    A position is measured against the reference capture, sigma_i^2 = u_i^2 +
    u_ref^2; the reference's share is common to all (taken as half the median
    variance, views being alike) and no ISO figure sees it.
    """
    s = np.asarray(sigma_um, float)
    ok = np.isfinite(s) & (s > 0)
    if not ok.any():
        return np.zeros_like(s)
    u_ref2 = 0.5 * float(np.median(s[ok] ** 2))
    return np.where(ok, np.sqrt(np.clip(s**2 - u_ref2, u_ref2, None)), 0.0)


def noise_corrected_max_abs(deviation_um: np.ndarray, valid: np.ndarray, sigma_um: np.ndarray) -> dict[str, Any]:
    """``single_run`` entries of max |deviation| with the noise's selection taken out (issue 35).

    The deviations share the reference capture's noise (a common offset, which a max |x| sees, unlike the
    ISO figures) beside each one's own (:func:`independent_sigma_um`): both are drawn
    (:func:`~lps_gui.core.metrology.extreme_noise.corrected_extreme`). Returns ``max_abs_deviation_um``
    (corrected) and ``max_abs_deviation_noise`` (measured, bias, u_noise, corrected); empty without two values.
    """
    x = np.asarray(deviation_um, float)
    ok = np.asarray(valid, bool) & np.isfinite(x)
    s = np.asarray(sigma_um, float)[ok]
    own = independent_sigma_um(s)
    common = np.sqrt(np.clip(s**2 - own**2, 0.0, None).mean()) if s.size else 0.0
    ext = corrected_extreme(x[ok], np.c_[np.diag(own), np.full(own.size, common)], "max_abs")
    if ext is None:
        return {}
    return {"max_abs_deviation_um": ext.corrected, "max_abs_deviation_noise": ext.to_dict()}


def _figure_vector(target_mm: np.ndarray, sign: np.ndarray, run: np.ndarray, dev: np.ndarray,
                   valid: np.ndarray) -> np.ndarray:
    """The NOISE_KEYS figures of one deviation set, NaN where undefined (the Monte Carlo's inner loop).

    The grouping into approaches is the plan's (cached across the draws of one plan); the arithmetic is
    :func:`bidirectional_figures`'s own, so the figures are the same numbers.
    """
    plan = _plan_of(target_mm, sign, run, valid)
    figures = None if plan is None else plan_figures(plan, dev)
    if figures is None:
        fig = bidirectional_figures(target_mm, sign, run, dev, valid)
        if fig is None:
            return np.full(len(NOISE_KEYS), np.nan)
        figures = {k: getattr(fig, k) for k in NOISE_KEYS}
    else:
        figures = figures[1]
    return np.array([np.nan if figures[k] is None else float(figures[k]) for k in NOISE_KEYS])


_PLANS: dict[tuple[Any, ...], ApproachPlan | None] = {}
MAX_PLANS = 128  # a planar session's lines (a 15 x 9 grid: 24), each drawn hundreds of times in turn


def _plan_of(target_mm: np.ndarray, sign: np.ndarray, run: np.ndarray, valid: np.ndarray) -> ApproachPlan | None:
    """:func:`approach_plan`, remembered by the plan's values: regrouping every draw was most of the Monte
    Carlo's time (a fifth of a planar estimate)."""
    r = np.asarray(run)
    key = (np.asarray(target_mm, float).tobytes(), np.asarray(sign).tobytes(), r.dtype.str,
           repr(r.tolist()) if r.dtype.kind == "O" else r.tobytes(),
           None if valid is None else np.asarray(valid, bool).tobytes())
    if key not in _PLANS:
        if len(_PLANS) >= MAX_PLANS:
            _PLANS.clear()
        _PLANS[key] = approach_plan(target_mm, sign, run, valid)
    return _PLANS[key]


def noise_bound(fig: Any, noise_um: np.ndarray) -> float:
    """Factor (<= 1) on the claimed per-view noise when the run-to-run scatter it would make is not there.

    Repeated approaches of a target differ by the stage's repeatability plus the noise, so their pooled
    variance bounds the noise's. A sigma that also carries model misfit (a carriage's angular motion
    against the constant-orientation model: 0.34 px where the corners have 0.016) would otherwise take
    out far more than noise (R of a stage with angles went to 0, truth 8 um). Only a claim the scatter
    rejects (chi-square, ``REJECT_P``) is replaced, by half the pooled variance (the scatter's split into
    repeatability and noise is unknown). 1 when no target was approached twice in one direction.
    """
    if fig is None:
        return 1.0
    tab = fig.per_target
    dof = np.concatenate([tab.n_up, tab.n_down]).astype(float) - 1.0
    var = np.concatenate([tab.std_up_um, tab.std_down_um]) ** 2
    keep = (dof > 0) & np.isfinite(var)
    claimed = float(np.mean(np.square(noise_um))) if np.size(noise_um) else 0.0
    if not keep.any() or claimed <= 0:
        return 1.0
    from scipy.stats import chi2  # scipy.stats costs lps estimate's start-up: only where the bound is tested

    n = float(np.sum(dof[keep]))
    pooled = float(np.sum(dof[keep] * var[keep]) / n)
    if pooled >= claimed * chi2.ppf(REJECT_P, n) / n:
        return 1.0  # the scatter could hold the claimed noise: keep it
    # the claim is rejected; the scatter is repeatability plus noise in unknown shares: take half of it
    return float(np.sqrt(0.5 * pooled / claimed))


def noise_corrected_iso(target_mm: np.ndarray, direction: np.ndarray, run: np.ndarray, deviation_um: np.ndarray,
                        valid: np.ndarray, noise_um: np.ndarray, draws: int = DRAWS) -> dict[str, dict[str, float]]:
    """Per ISO figure: the measured value, the noise's bias and standard uncertainty, the corrected value (um).

    Parameters
    ----------
    target_mm, direction, run, deviation_um, valid : per capture, as :func:`bidirectional_figures`.
    noise_um : shape (K,), each capture's independent noise (1 sigma, um; see :func:`independent_sigma_um`).

    Returns
    -------
    ``{key: {"measured", "bias", "noise_scale", "u_noise", "corrected"}}`` for the figures the data define
    (``u_noise``: the noise's standard uncertainty of the corrected figure; ``noise_scale``: :func:`noise_bound`);
    ``corrected`` is the measured value minus the bias, never below 0 for a span or range.
    """
    t = np.asarray(target_mm, float)
    sign = direction_signs(direction)
    r = np.asarray(run)
    x = np.asarray(deviation_um, float)
    ok = np.asarray(valid, bool) & np.isfinite(x)
    noise = np.where(ok, np.nan_to_num(np.asarray(noise_um, float)), 0.0)
    measured = _figure_vector(t, sign, r, x, ok)
    if not np.isfinite(measured).any():
        return {}
    scale = noise_bound(bidirectional_figures(t, sign, r, x, ok), noise[ok])
    measured, bias, sd = simex(lambda v: _figure_vector(t, sign, r, v, ok), x, scale * noise, draws)
    out: dict[str, dict[str, float]] = {}
    _corrected(out, measured, bias, sd, scale)
    _bidirectional_at_least_each_way(out)
    return out


def noise_corrected_worst(lines: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
                          draws: int = DRAWS) -> tuple[int, dict[str, dict[str, float]]] | None:
    """The figures of the line with the largest accuracy A, the noise taken out *with that choice*.

    ``lines``: per line (target_mm, direction, run, deviation_um, noise_um) as :func:`noise_corrected_iso`.
    Why: a planar axis is judged on its worst line; corrected one line at a time, each line's figure is
    unbiased but scatters by its noise, and the largest of 4-6 of them picks the largest draw (the
    small-planar preset: A X 125-300 um against a truth of ~10 um). Here every Monte Carlo draw perturbs all
    lines and picks its own worst line, so the bias and the spread are those of the selection. The
    extrapolant is the square's (linear in lambda, the root taken): with two runs each s_j has one degree of
    freedom and the worst line's A and R grow like sqrt(s^2 + (1 + lambda) sigma^2), which a quadratic in
    lambda follows badly towards lambda = -1 (it left +25-33 um of A and R on U 46-53 um where the noise,
    8 um a view, is near the figure: the campaign's planar cell with realism on; coverage 88-90 %). u adds
    ``SELECTION_RESIDUAL`` times the correction for what that extrapolant leaves. Returns (index of the line
    measured worst, figures as :func:`noise_corrected_iso`), or None without a line with A.
    """
    if not lines:
        return None
    parts = []
    for t, d, r, x, noise in lines:
        sign = direction_signs(d)
        ok = np.isfinite(np.asarray(x, float))
        noise = np.where(ok, np.nan_to_num(np.asarray(noise, float)), 0.0)
        scale = noise_bound(bidirectional_figures(t, sign, r, x, ok), noise[ok])
        parts.append((np.asarray(t, float), sign, np.asarray(r), ok, scale * noise, scale))
    edges = np.cumsum([0] + [p[0].size for p in parts])

    def per_line(v: np.ndarray) -> np.ndarray:
        return np.array([_figure_vector(t, sign, r, v[edges[i]:edges[i + 1]], ok)
                         for i, (t, sign, r, ok, _, _) in enumerate(parts)])

    x = np.concatenate([np.asarray(ln[3], float) for ln in lines])
    figs = per_line(x)
    # A over both directions; a plan of one direction has that direction's A only
    a = next((NOISE_KEYS.index(k) for k in ("A_um", "A_up_um", "A_down_um")
              if np.isfinite(figs[:, NOISE_KEYS.index(k)]).any()), None)
    if a is None:
        return None
    acc = figs[:, a]

    def worst(v: np.ndarray) -> np.ndarray:
        f = per_line(v)
        return f[int(np.nanargmax(f[:, a]))] if np.isfinite(f[:, a]).any() else np.full(len(NOISE_KEYS), np.nan)

    measured, bias, sd = simex(worst, x, np.concatenate([p[4] for p in parts]), draws, squared=True)
    out: dict[str, dict[str, float]] = {}
    scale = min(p[5] for p in parts)
    _corrected(out, measured, bias, sd, scale)
    for key, c in out.items():  # the extrapolation's residual bias (see above)
        c["u_noise"] = float(np.hypot(c["u_noise"], SELECTION_RESIDUAL * c["bias"]))
        c["selection"] = len(parts)
    _bidirectional_at_least_each_way(out)
    return int(np.nanargmax(acc)), out


def _bidirectional_at_least_each_way(out: dict[str, dict[str, float]]) -> None:
    """A, R, E over both directions are at least each direction's (ISO 230-2's definitions); corrected one by
    one, a noise-dominated session could break that (A 12 um beside A down 95 um, truth 17 and 15). The
    figure over both directions rests on all the data: a direction's figure is capped at it. (Raising the
    both-ways figure instead made R's mean (error/sigma)^2 2.27 on line-both with realism, 1.81 without.)"""
    for letter in ("A", "R", "E"):
        bi = out.get(f"{letter}_um")
        for key in (f"{letter}_up_um", f"{letter}_down_um"):
            if bi is not None and key in out and out[key]["corrected"] > bi["corrected"]:
                out[key]["corrected"] = bi["corrected"]


def _corrected(out: dict[str, dict[str, float]], measured: np.ndarray, bias: np.ndarray, sd: np.ndarray,
               scale: float) -> None:
    """Fill ``out`` per defined figure: measured, bias, the corrected value and its noise u."""
    for i, key in enumerate(NOISE_KEYS):
        if not np.isfinite(measured[i]):
            continue
        corrected = measured[i] - bias[i]
        if key != "B_mean_um":  # spans, ranges, max |B_j|: not negative
            corrected = max(corrected, 0.0)
        u = SIMEX_U_FACTOR * sd[i]
        if scale < 1.0:  # the noise's share of the scatter is unknown (0 to all of it): the bias 0 to twice this one
            u = float(np.hypot(u, bias[i] / np.sqrt(3.0)))
        out[key] = {"measured": float(measured[i]), "bias": float(bias[i]), "noise_scale": scale,
                    "u_noise": float(u), "corrected": float(corrected)}


def apply_noise_correction(iso: dict[str, Any], corr: dict[str, dict[str, float]]) -> dict[str, Any]:
    """results.json ``iso230_2`` with the corrected figures and ``noise_correction`` (measured, bias, sd)."""
    out = dict(iso)
    for key, c in corr.items():
        out[key] = c["corrected"]
    out["noise_correction"] = corr
    out["notes"] = list(iso.get("notes") or []) + [
        "A, E, M, R, B: the camera's per-view noise (which adds to every s_j and to the extremes) is taken out by "
        "Monte Carlo; the measured values, the noise's bias and u are in noise_correction; the per-target table "
        "is of the measured deviations."]
    return out
