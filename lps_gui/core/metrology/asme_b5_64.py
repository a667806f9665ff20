"""ASME B5.64 (single-axis linear positioning systems) figures a camera measures, as pure math.

* The ISO 230-2 figures under both names (:data:`FIGURE_NAMES`): ASME B5.64
  reports the same bidirectional accuracy and repeatability as ISO 230-2.
* The test uncertainty ratio :func:`tur`: specification
  tolerance over the expanded uncertainty U (k = 2) of the figure compared.
* The incremental-step test (:func:`incremental_step_figures`): small
  commanded steps forward and back, several frames averaged per stop; each
  step achieved against the command, whether the measurement resolves it,
  whether the stage sticks (a step that did not move), and the minimum
  incremental motion (the smallest commanded step every resolved step of
  which is within the tolerance).
* Settling (:func:`settling_figures`): position against time after a move;
  a damped oscillation fitted to it gives the time to settle within a band
  (the last time outside it), beside the frames' own crossing.

No I/O, no Qt: numpy and scipy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.truth.stage_errors import Vibration

# ISO 230-2 symbol and results.json key -> (ISO 230-2 name, ASME B5.64 name); the same figure under both
FIGURE_NAMES: tuple[tuple[str, str, str, str], ...] = (
    ("A", "A_um", "accuracy of positioning A (bidirectional)", "bidirectional positioning accuracy"),
    ("A\u2191", "A_up_um", "unidirectional accuracy of positioning A\u2191", "unidirectional positioning accuracy (+)"),
    ("A\u2193", "A_down_um", "unidirectional accuracy of positioning A\u2193", "unidirectional positioning accuracy (\u2212)"),
    ("R", "R_um", "repeatability of positioning R (bidirectional)", "bidirectional repeatability"),
    ("R\u2191", "R_up_um", "unidirectional repeatability R\u2191", "unidirectional repeatability (+)"),
    ("R\u2193", "R_down_um", "unidirectional repeatability R\u2193", "unidirectional repeatability (\u2212)"),
    ("E", "E_um", "systematic positioning error E (bidirectional)", "bidirectional systematic deviation"),
    ("M", "M_um", "mean positioning error M", "mean bidirectional positional deviation"),
    ("B", "B_um", "reversal value B", "reversal error (lost motion)"),
)
INCREMENTAL_MAX_UM = 100.0  # consecutive stops closer than this are an incremental step, farther a traverse
STEP_TOLERANCE = 0.5  # a step is achieved within +-50 % of its command (contract value; ASME leaves it to the parties)
SETTLE_TAIL = 0.25  # the last quarter of a stop's frames is where the carriage rests


def tur(tolerance: float | None, u_k2: float | None) -> float | None:
    """Specification tolerance over U (k = 2); None when either is missing (never invented)."""
    if tolerance is None or u_k2 is None or not (u_k2 > 0) or not math.isfinite(float(tolerance)):
        return None
    return float(tolerance) / float(u_k2)


def named_figures(iso: dict[str, Any] | None, figures_k2: dict[str, Any] | None) -> list[dict[str, Any]]:
    """The ISO 230-2 figures a session has, each under its ISO 230-2 and ASME B5.64 names, with U (k = 2)."""
    iso, u = iso or {}, figures_k2 or {}
    return [{"symbol": sym, "key": key, "iso230_2": iso_name, "asme_b5_64": asme_name,
             "value_um": float(iso[key]), "U_um": None if u.get(key) is None else float(u[key])}
            for sym, key, iso_name, asme_name in FIGURE_NAMES if iso.get(key) is not None]


# ----------------------------------------------------------------------------- incremental step


@dataclass(frozen=True)
class StopMeans:
    """Stops of a session with their frames averaged: shape (S,) each."""

    target_mm: np.ndarray
    position_mm: np.ndarray  # mean measured position of the stop's frames
    direction: np.ndarray  # +1 / -1: the pass
    pass_id: np.ndarray  # (run, direction) pass the stop belongs to
    n_frames: np.ndarray


def incremental_steps(stops: StopMeans, max_step_um: float = INCREMENTAL_MAX_UM) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (from, to) of consecutive stops of one pass that are an incremental step (not a traverse)."""
    same_pass = stops.pass_id[1:] == stops.pass_id[:-1]
    dt_um = 1e3 * np.abs(np.diff(stops.target_mm))
    step = same_pass & (dt_um > 0) & (dt_um <= max_step_um)
    i = np.flatnonzero(step)
    return i, i + 1


def incremental_step_figures(commanded_um: np.ndarray, achieved_um: np.ndarray, sigma_um: np.ndarray,
                             tolerance: float = STEP_TOLERANCE) -> dict[str, Any]:
    """The incremental-step test's figures from signed steps (um) and each step's 1-sigma.

    Parameters
    ----------
    commanded_um : shape (n,), each step as commanded (signed: backward steps negative).
    achieved_um : shape (n,), the measured displacement between the two stops' averaged positions.
    sigma_um : shape (n,), 1-sigma of ``achieved_um`` (noise of both stops' means, correlations counted).
    tolerance : a step is achieved within +-``tolerance`` x its command.

    A step is *resolved* when its U (k = 2) is below its command (a missed
    step and a made one lie more than U apart); *achieved* unless it is
    outside the tolerance by more than its U (ISO 14253-1: a miss needs
    evidence); *stuck* when it moved less than half its command. The stage
    *sticks* when more steps stuck than the noise alone would make (their
    expected number plus 3 sigma, binomial). The minimum incremental motion
    is the smallest commanded size whose steps are resolved, do not stick
    and are achieved (95 % or more; None when no size is). Per step, *stuck* means
    below half and not achieved (a miss needs evidence, as above): never both (issue 37: a step that
    moved -0.44 um of 2 um with a 0.75 um sigma was both); the sticking test counts every step below half.
    """
    from scipy.special import ndtr

    c, a, s = (np.asarray(v, dtype=float).ravel() for v in (commanded_um, achieved_um, sigma_um))
    size = np.abs(c)
    along = a * np.sign(c)  # the displacement in the commanded direction
    band = tolerance * size
    resolved = np.isfinite(s) & (2.0 * s < size)
    achieved = np.abs(along - size) <= band + 2.0 * s
    below_half = along < 0.5 * size  # counted against noise's expectation: does the stage stick?
    stuck = below_half & ~achieved  # a step is stuck with evidence, never both stuck and achieved
    chance = ndtr(-0.5 * size / np.where(s > 0, s, np.inf))  # a made step measured below half its command
    per_size = []
    mim, sticks = None, False
    for d in np.unique(np.round(size, 6)):
        sel = np.isclose(size, d, atol=1e-6)
        expected = float(chance[sel].sum())
        n_stuck = int(below_half[sel].sum())
        size_sticks = bool(resolved[sel].all() and n_stuck > expected + 3.0 * math.sqrt(expected + 1.0))
        ok = bool(resolved[sel].all() and not size_sticks and achieved[sel].mean() >= 0.95)
        z2 = float(np.mean(((along[sel] - d) / s[sel]) ** 2))
        per_size.append({"commanded_um": float(d), "n_steps": int(sel.sum()), "n_resolved": int(resolved[sel].sum()),
                         "n_achieved": int(achieved[sel].sum()), "n_stuck": n_stuck,
                         "n_stuck_by_noise": expected, "sticks": size_sticks, "scatter_z2": z2,
                         "mean_achieved_um": float(np.mean(along[sel])), "all_achieved": ok})
        sticks |= size_sticks
        if ok and mim is None:
            mim = float(d)
    return {
        "n_steps": int(c.size), "n_resolved": int(resolved.sum()), "n_achieved": int(achieved.sum()),
        "n_stuck": int(below_half.sum()), "sticks": bool(sticks), "tolerance": float(tolerance),
        "max_step_sigma_um": float(np.max(s)) if s.size else None,
        "median_step_sigma_um": float(np.median(s)) if s.size else None,
        "minimum_incremental_motion_um": mim,
        "sizes": per_size,
        "steps": [{"commanded_um": float(ci), "achieved_um": float(ai), "sigma_um": float(si), "resolved": bool(r),
                   "achieved": bool(ok), "stuck": bool(st), "below_half": bool(bh)}
                  for ci, ai, si, r, ok, st, bh in zip(c, a, s, resolved, achieved, stuck, below_half)],
    }


# ----------------------------------------------------------------------------- settling


def _damped(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    rest, amp, decay, freq, phase = params
    return rest + amp * np.exp(-t / max(decay, 1e-9)) * np.cos(2.0 * math.pi * freq * t + phase)


def _linear_fit(t: np.ndarray, x: np.ndarray, decay: float, freq: float) -> tuple[np.ndarray, float]:
    """rest, amplitude, phase of a damped cosine with ``decay`` and ``freq`` fixed (linear least squares)."""
    e = np.exp(-t / decay)
    w = 2.0 * math.pi * freq * t
    A = np.column_stack([np.ones_like(t), e * np.cos(w), e * np.sin(w)])
    coef, *_ = np.linalg.lstsq(A, x, rcond=None)
    ssr = float(np.sum((A @ coef - x) ** 2))
    rest, c, s = coef
    return np.array([rest, math.hypot(c, s), decay, freq, math.atan2(-s, c)]), ssr


def fit_ringing(t_s: np.ndarray, x_um: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """A damped cosine rest + A exp(-t/tau) cos(2 pi f t + phi) fitted to one stop's positions after its move.

    The frequency starts at the spectrum's peak, the decay at the best of a
    log grid (both with the linear parameters solved exactly), then all five
    are refined by scipy's least squares. Returns (params (5,), their
    covariance (5, 5), residual sigma um) or None with too few frames.
    """
    from scipy.optimize import least_squares

    t, x = np.asarray(t_s, dtype=float), np.asarray(x_um, dtype=float)
    ok = np.isfinite(t) & np.isfinite(x)
    t, x = t[ok], x[ok]
    if t.size < 8 or np.ptp(t) <= 0:
        return None
    dt = float(np.median(np.diff(np.sort(t))))
    span = float(np.ptp(t))
    detrended = x - np.mean(x[-max(2, int(SETTLE_TAIL * x.size)):])
    n = 8 * int(2 ** math.ceil(math.log2(x.size)))
    spectrum = np.abs(np.fft.rfft(detrended, n))
    freqs = np.fft.rfftfreq(n, dt)
    freq0 = float(freqs[1 + int(np.argmax(spectrum[1:]))])
    best = min((_linear_fit(t, x, tau, freq0) for tau in np.geomspace(2 * dt, span, 24)), key=lambda p: p[1])[0]
    fit = least_squares(lambda p: _damped(p, t) - x, best, x_scale="jac")
    dof = max(t.size - 5, 1)
    sigma = math.sqrt(2.0 * fit.cost / dof)
    J = fit.jac
    try:
        cov = sigma ** 2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((5, 5), np.nan)
    params = fit.x.copy()
    if params[1] < 0:  # one sign convention: amplitude positive, phase shifted by pi
        params[1], params[4] = -params[1], params[4] + math.pi
    params[4] = (params[4] + math.pi) % (2.0 * math.pi) - math.pi
    return params, cov, sigma


def settling_time_from_frames(t_s: np.ndarray, x_um: np.ndarray, band_um: float) -> float | None:
    """The time of the first frame after which every frame is within +-``band_um`` of rest (None: never)."""
    t, x = np.asarray(t_s, dtype=float), np.asarray(x_um, dtype=float)
    outside = np.flatnonzero(np.abs(x) > band_um)
    if outside.size == 0:
        return float(t[0])
    last = int(outside[-1])
    return None if last + 1 >= t.size else float(t[last + 1])


def settling_figures(t_s: np.ndarray, x_um: np.ndarray, band_um: float, k: float = 2.0) -> dict[str, Any] | None:
    """The settling test of one stop: position (um, any zero) against time since the move ended (s).

    Returns the fitted ringing (rest, amplitude, decay, frequency, phase with
    sigmas), the settling time within +-``band_um`` of rest from the fit
    (the figure) with its U (k = 2), and the frames' own crossing; None when
    the stop has too few frames.
    """
    got = fit_ringing(t_s, x_um)
    if got is None:
        return None
    p, cov, sigma = got
    rest, amp, decay, freq, phase = (float(v) for v in p)
    ringing = Vibration(amplitude_um=amp, frequency_hz=freq, decay_s=decay, phase_rad=phase)
    settle = ringing.settling_time_s(band_um)
    var = np.diag(cov)
    log_ratio = math.log(amp / band_um) if amp > band_um else 0.0
    # the envelope tau ln(A/band) carries the fit's uncertainty; a frame interval bounds where between frames it is
    dt = float(np.median(np.diff(np.sort(np.asarray(t_s, dtype=float)))))
    var_settle = (log_ratio ** 2) * var[2] + (decay / amp) ** 2 * var[1] + dt ** 2 / 12.0 if amp > 0 else np.nan
    t = np.asarray(t_s, dtype=float)
    frames = settling_time_from_frames(t, np.asarray(x_um, dtype=float) - rest, band_um)
    return {
        "band_um": float(band_um), "n_frames": int(t.size), "frame_interval_s": dt, "record_s": float(np.nanmax(t)),
        "settling_time_s": float(settle), "settling_time_U_s": float(k * math.sqrt(var_settle)),
        "settling_time_frames_s": frames, "residual_sigma_um": float(sigma),
        "rest_um": rest, "amplitude_um": amp, "decay_s": decay, "frequency_hz": freq, "phase_rad": phase,
        "sigmas": dict(zip(("rest_um", "amplitude_um", "decay_s", "frequency_hz", "phase_rad"),
                           (float(math.sqrt(v)) if v >= 0 else None for v in var))),
    }
