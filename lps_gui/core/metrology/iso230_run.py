"""Single-run figures of SPEC section 5 and the helpers the ISO figures share.

One run of a stage (or all valid captures of a session, one offset per run
and direction) gives: mean step and step std between adjacent targets, max
|deviation|, the linear scale error (ppm) from a least-squares line of the
deviation against the target, and the periodic error, the peak of the
spectrum of the detrended deviation (a lead-screw pitch). Pure math, no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from lps_gui.core.metrology.iso230_spectrum import UNDEFINED_NOTE, Spectrum, deviation_spectrum
from lps_gui.errors import InputError

DEVIATION = "deviation_um"  # the deviations' name among the capture arrays (the argument's, in messages)

TARGET_TOL_MM = 1e-6  # targets closer than this are one target P_j


def finite_or_none(v: Any) -> float | None:
    """A finite float, or None (JSON has no NaN)."""
    if v is None:
        return None
    v = float(v)
    return v if np.isfinite(v) else None


def json_value(v: Any) -> Any:
    """Dataclass field value -> JSON-ready value (arrays to lists, NaN to None)."""
    if isinstance(v, np.ndarray):
        if v.dtype.kind in "iub":
            return v.astype(int).tolist()
        return [None if not np.isfinite(e) else float(e) for e in v.astype(float)]
    if hasattr(v, "to_dict"):
        return v.to_dict()
    if isinstance(v, (list, tuple)):
        return [json_value(e) for e in v]
    if isinstance(v, (float, np.floating)):
        return finite_or_none(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    return v


class JsonDataclass:
    """Mixin for the figure dataclasses: ``to_dict()`` gives what results.json stores."""

    def to_dict(self) -> dict[str, Any]:
        """Fields as JSON-ready values: lists of floats, None for undefined."""
        return {f.name: json_value(getattr(self, f.name)) for f in fields(self)}  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- input checks


def capture_arrays(target_mm: Any, deviation_um: Any, valid: Any, **others: Any) -> dict[str, np.ndarray]:
    """Check that every per-capture array has shape (K,); valid defaults to all True, NaN is invalid."""
    t = np.asarray(target_mm, dtype=float).ravel()
    x = np.asarray(deviation_um, dtype=float).ravel()
    out = {"target_mm": t, DEVIATION: x}
    for name, v in others.items():
        if v is not None:
            out[name] = np.asarray(v).ravel()
    ok = np.ones(t.shape, bool) if valid is None else np.asarray(valid, dtype=bool).ravel()
    out["valid"] = ok
    for name, v in out.items():
        if v.shape != t.shape:
            raise InputError(f"accuracy figures: {name} has {v.size} values but target_mm has {t.size}; "
                             "give one value per capture")
    out["valid"] = ok & np.isfinite(t) & np.isfinite(x)
    return out


def target_index(target_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets matched within TARGET_TOL_MM: (unique targets (m,) ascending, index (K,) into them)."""
    key = np.round(target_mm / TARGET_TOL_MM).astype(np.int64)
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    return target_mm[first], inv.ravel()


# ----------------------------------------------------------------------------- single run


@dataclass
class RunFigures(JsonDataclass):
    """Single-run figures of SPEC 5 (one run, or all valid captures with one offset per group)."""

    n_captures: int  # valid captures used
    mean_step_mm: float | None  # mean distance between measured positions of adjacent targets
    step_std_um: float | None  # std (ddof=1) of those steps
    max_abs_deviation_um: float | None  # max |x|
    deviation_span_um: float | None  # max x - min x
    scale_ppm: float | None  # slope of the least-squares line x(P), in um/m
    scale_sigma_ppm: float | None  # its standard uncertainty
    periodic_amplitude_um: float | None  # sine amplitude of the spectrum's peak (detrended x); None: not defined
    periodic_period_mm: float | None  # period of that peak (a lead-screw pitch)
    spectrum: Spectrum | None
    notes: list[str] = field(default_factory=list)


JUMP_RATIO = 10.0  # a commanded move over this many times the median commanded step is a jump between places, not a step


def _steps_mm(t: np.ndarray, measured: np.ndarray, ok: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, int]:
    """Steps between measured positions of adjacent targets within each group (mm), and the jumps left out.

    The target grid of a group includes invalid captures, so an outlier leaves
    a hole instead of a double step; frames at one target are averaged. A move
    of more than JUMP_RATIO times the median commanded step is the plan's jump
    to its next place (a min-step test's 2 um steps at three places), not a step:
    its millimetres would swamp the step std.
    """
    steps, commanded = [], []
    for g in np.unique(group):
        sel = (group == g) & np.isfinite(t)
        targets, j = target_index(t[sel])
        n = np.bincount(j[ok[sel]], minlength=targets.size)
        with np.errstate(invalid="ignore", divide="ignore"):
            pos = np.bincount(j[ok[sel]], measured[sel][ok[sel]], minlength=targets.size) / n
        steps.append(np.diff(pos))
        commanded.append(np.diff(targets))
    if not steps:
        return np.empty(0), 0
    s, c = np.concatenate(steps), np.abs(np.concatenate(commanded))
    jump = c > JUMP_RATIO * np.median(c) if c.size else np.zeros(0, bool)
    keep = np.isfinite(s) & ~jump
    return s[keep], int((np.isfinite(s) & jump).sum())


def _within_groups(t: np.ndarray, group: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """The scale fit x = offset_g + b (t - t_mean) in closed form, weights ``w`` (1/sigma^2).

    With one offset per group the slope only sees t centred in its group:
    ``tc = t - (weighted mean of t in its group)``, and b = sum(w tc x) / S
    with S = sum(w tc^2). Returns (g, tc, S, determined): g the group index
    of each point; ``determined`` is False when t is (numerically) constant
    within every group, where the design's rank is short (the tolerance of
    numpy's matrix_rank, on the Frobenius norm of the weighted design).
    O(n), where the SVD of the (n, 1 + groups) design cost O(n groups^2) and
    seconds under a loaded BLAS at K = 5000 with 20 groups.
    """
    _, g = np.unique(group, return_inverse=True)
    g = g.ravel()
    n_groups = int(g.max()) + 1 if g.size else 0
    w_sum = np.bincount(g, w, minlength=n_groups)
    tc = t - (np.bincount(g, w * t, minlength=n_groups) / w_sum)[g]
    S = float(np.sum(w * tc * tc))
    frobenius2 = float(np.sum(w * (t - t.mean()) ** 2) + np.sum(w))
    tol = max(t.size, 1 + n_groups) * np.finfo(float).eps
    return g, tc, S, S > tol * tol * frobenius2 and t.size > n_groups


def scale_functional(t: np.ndarray, group: np.ndarray, w: np.ndarray | None = None) -> np.ndarray | None:
    """The row ``a`` (n,) with slope ``b = a @ x`` of the scale fit x = offset_g + b (t - t_mean).

    Weighted by ``w`` (1/sigma^2) when given. The slope is linear in the
    deviations, so a caller holding their full covariance C gets the slope's
    sigma as sqrt(a C a^T) (correlations included); None when the groups and
    targets do not determine a slope. ``a = w tc / S`` (:func:`_within_groups`).
    """
    w = np.ones_like(t) if w is None else np.asarray(w, dtype=float)
    _, tc, S, determined = _within_groups(t, group, w)
    return w * tc / S if determined else None


def _scale_fit(t: np.ndarray, x: np.ndarray, w: np.ndarray | None, group: np.ndarray
               ) -> tuple[np.ndarray, float | None, float | None]:
    """Least-squares x = offset_g + b (t - t_mean): (residual (n,), b in um/mm, sigma of b).

    Weighted by 1/sigma^2 when given; the slope sigma is then the formal one
    (independent deviations) scaled up by sqrt(chi2/dof) when the scatter
    exceeds the sigmas (Birge ratio). The estimator replaces it with the
    sigma from the full covariance of the positions (same row, :func:`scale_functional`).
    The residual is x minus its group's weighted mean and the slope's part
    (the least-squares residual, whatever the rank).
    """
    ww = np.ones_like(t) if w is None else np.asarray(w, dtype=float)
    g, tc, S, determined = _within_groups(t, group, ww)
    n_groups = int(g.max()) + 1 if g.size else 0
    xc = x - (np.bincount(g, ww * x, minlength=n_groups) / np.bincount(g, ww, minlength=n_groups))[g]
    if not determined:
        return xc, None, None
    row = ww * tc / S
    b = float(row @ x)
    resid = xc - b * tc
    dof = t.size - (1 + n_groups)
    if dof <= 0:
        return resid, b, None
    chi2_red = float(np.sum(ww * resid**2) / dof)
    var = float(np.sum(row**2 / ww)) * (chi2_red if w is None else max(1.0, chi2_red))
    return resid, b, float(np.sqrt(var))


def fit_weights_sigma_um(sigma_um: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """The per-capture sigma the scale fit weights by (1/sigma^2): the positions' noise sigma, the reference
    capture's (0 by the gauge) and any other non-positive one replaced by the median positive one.

    One rule for the estimate and for its truth (sim/truth_figures.py): the scale is a weighted slope, and on
    a profile that is not a line (periodic error, backlash) the weighted and the unweighted slope differ
    (-7 ppm on the two-depth flat stage, where the sigma doubles along the travel)."""
    s = np.asarray(sigma_um, dtype=float)
    ok = np.asarray(valid, dtype=bool)
    positive = ok & (s > 0)
    return np.where(ok & ~(s > 0), np.median(s[positive]) if positive.any() else 1.0, s)


def single_run_figures(target_mm: np.ndarray, deviation_um: np.ndarray, valid: np.ndarray | None = None,
                       sigma_um: np.ndarray | None = None, *, group: np.ndarray | None = None) -> RunFigures:
    """Single-run figures of SPEC section 5 from deviations x = measured - target.

    Parameters
    ----------
    target_mm, deviation_um : shape (K,).
    valid : shape (K,) bool or None; outliers (False) and NaN deviations are left out.
    sigma_um : shape (K,) or None; 1-sigma of each deviation, weights the scale fit by 1/sigma^2.
    group : shape (K,) or None; runs/directions when several are pooled: steps are taken
        within a group and the scale line gets one offset per group (removes backlash).

    Returns
    -------
    RunFigures: mean step (mm) and step std (um) between adjacent targets, max |x|, span of x,
    scale error (ppm, slope of the least-squares line of x against target) with its sigma, and
    the periodic error: the peak of the spectrum of the detrended x (period mm, sine amplitude
    um), with the spectrum for plotting. Figures the data cannot give are None (see ``notes``).
    """
    a = capture_arrays(target_mm, deviation_um, valid, sigma_um=sigma_um, group=group)
    ok, t_all, x_all = a["valid"], a["target_mm"], a[DEVIATION]
    grp_all = a.get("group", np.zeros(t_all.shape, int))
    notes: list[str] = []
    n_bad = int((~ok).sum())
    if n_bad:
        notes.append(f"{n_bad} capture(s) left out as invalid (outliers or no position).")
    t, x, grp = t_all[ok], x_all[ok], grp_all[ok]
    w = None
    if sigma_um is not None:
        s = a["sigma_um"].astype(float)[ok]
        if not np.all(np.isfinite(s) & (s > 0)):
            raise InputError("sigma_um must be positive and finite for every valid capture")
        w = 1.0 / s**2
    if t.size == 0:
        return RunFigures(0, None, None, None, None, None, None, None, None, None, notes + ["No valid capture."])

    steps, jumps = _steps_mm(t_all, t_all + x_all * 1e-3, ok, grp_all)
    if jumps:
        notes.append(f"{jumps} jump(s) between the plan's places left out of the step figures.")
    mean_step = float(steps.mean()) if steps.size else None
    step_std = float(steps.std(ddof=1) * 1e3) if steps.size > 1 else None
    if steps.size == 0:
        notes.append("No two adjacent targets with valid captures: no step figures.")

    scale = scale_sigma = None
    resid = x - x.mean()
    if np.ptp(t) > 0:
        resid, b, sb = _scale_fit(t, x, w, grp)
        scale = None if b is None else b * 1e3  # um/mm -> ppm
        scale_sigma = None if sb is None else sb * 1e3
    else:
        notes.append("All valid captures at one target: no scale error.")

    spec = deviation_spectrum(t, resid, w)
    if spec is None:
        notes.append("Fewer than 4 valid targets: no periodic error.")
    elif spec.peak_amplitude_um is None:
        notes.append(UNDEFINED_NOTE)
    return RunFigures(
        n_captures=int(t.size), mean_step_mm=mean_step, step_std_um=step_std,
        max_abs_deviation_um=float(np.abs(x).max()), deviation_span_um=float(np.ptp(x)),
        scale_ppm=scale, scale_sigma_ppm=scale_sigma,
        periodic_amplitude_um=None if spec is None else spec.peak_amplitude_um,
        periodic_period_mm=None if spec is None else spec.peak_period_mm,
        spectrum=spec, notes=notes)
