"""Uncertainty budget of a position measurement, GUM / ISO/TR 230-9 style.

Each source is a row: its standard uncertainty ``value`` in its own unit, a
sensitivity coefficient ``c`` (um per unit) and the contribution ``u = |c| value``
in um for a displacement over the measured travel L. The combined standard
uncertainty is the root sum of squares (sources taken as uncorrelated), the
expanded uncertainty U = k u_c with k = 2 (about 95 %).

Sources: corner noise of the measured view and of the reference (first)
view, the intrinsics' covariance (both type A, from the fit and the
calibration), the board's square size (type B, from the board's
certificate), the board thermometer and expansion coefficient (type B), the
stage's uncorrected expansion relative to 20 C (rectangular, type B) and an
Abbe offset estimate from the noise-corrected spread of pitch and yaw
times the camera-board distance, which is shown but not in U: the positions
are the displacement at the board plane (README "Abbe offset"), and the row
is what the camera centre's would differ by (a tool point's error is on the
error-motions page). A source that was not recorded stays in the table with
contribution None and a note; it is not in U.

Per-figure uncertainties (:func:`figure_uncertainties`): figures that are
positions or spans of positions (A, E, M, max |deviation|) carry U; figures
that are differences at one target (R, B) carry only the noise terms, which
do not cancel there (scale and temperature terms do). No I/O, no Qt.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from lps_gui.core.metrology.environment import Environment

COVERAGE_FACTOR = 2.0
NOISE_SOURCES = ("corner noise", "reference view noise")
ABBE_SOURCE = "Abbe offset"  # in the table, not in U: the positions are at the board plane (see :func:`_abbe_row`)
TILT_DEGREE = 3  # a carriage's pitch and yaw along the travel: smooth, a cubic follows it
TILT_K = 3.0  # a tilt spread counts when it exceeds the noise share by this many of its sd


@dataclass(frozen=True)
class BudgetRow:
    """One source of the budget; ``contribution_um`` None when the source was not recorded."""

    source: str
    type: str  # "A" (statistics of this measurement) or "B" (other knowledge)
    value: float | None  # standard uncertainty of the input quantity, in ``unit``
    unit: str
    sensitivity: float | None  # um per ``unit``
    contribution_um: float | None
    note: str = ""


@dataclass(frozen=True)
class BudgetInputs:
    """What the budget needs from one estimation (arrays over the used views)."""

    travel_mm: float
    square_mm: float
    sigma_px: float
    sigma_um: np.ndarray  # noise-only 1-sigma per used view (relative to the reference)
    sigma_total_um: np.ndarray  # with the intrinsics' covariance (and the lens misfit, when the session has one)
    sigma_lens_um: np.ndarray | None = None  # the lens-model misfit's share of each position (issue 35)
    abbe_lever_mm: tuple[float, float] | None = None  # camera -> board centre along v2 (pitch's lever), along v1 (yaw's)
    tilt_urad: np.ndarray | None = None  # (n, 2) pitch and yaw per used view
    tilt_sigma_urad: np.ndarray | None = None  # (n, 2) their 1-sigma
    target_mm: np.ndarray | None = None  # (n,) targets of the used views (for the smooth tilt curve)
    tilt_resolved: tuple[bool, bool] | None = None  # pitch (EBX), yaw (ECX) resolved by the error motions; None: not judged


def _rms(v: np.ndarray) -> float:
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v**2))) if v.size else math.nan


def budget_rows(x: BudgetInputs, env: Environment) -> list[BudgetRow]:
    """The budget's rows for a displacement over the travel ``x.travel_mm``."""
    L = float(x.travel_mm)
    rows: list[BudgetRow] = []
    # a position is relative to the reference capture: sigma_i^2 = u_view^2 + u_ref^2 with u_view ~ u_ref
    per_view = _rms(x.sigma_um[np.asarray(x.sigma_um) > 0]) / math.sqrt(2.0)
    c_px = per_view / x.sigma_px if x.sigma_px > 0 and math.isfinite(per_view) else None
    for source, note in (("corner noise", "RMS 1-sigma over the views / sqrt 2 (noise of the measured view)"),
                         ("reference view noise", "the first capture's noise, part of every position")):
        rows.append(BudgetRow(source, "A", x.sigma_px, "px", c_px, _finite(per_view), note))
    lens = np.zeros_like(np.asarray(x.sigma_um, float)) if x.sigma_lens_um is None else np.nan_to_num(x.sigma_lens_um)
    extra = np.sqrt(np.clip(np.asarray(x.sigma_total_um, float) ** 2 - np.asarray(x.sigma_um, float) ** 2 - lens**2,
                            0, None))
    intr = _rms(extra)
    rows.append(BudgetRow("intrinsics", "A", _finite(intr), "\u00b5m", 1.0 if math.isfinite(intr) else None,
                          _finite(intr), "calibration covariance propagated through d s / d intrinsics (RMS)"))
    if x.sigma_lens_um is not None and np.any(lens > 0):
        u_lens = _rms(lens)
        rows.append(BudgetRow("lens model", "B", _finite(u_lens), "\u00b5m", 1.0, _finite(u_lens),
                              "the misfit of the 5-coefficient lens model the residuals show, through each view's pose "
                              "(RMS; smooth over the image, so it does not average out over the stops)"))
    n_squares = L / x.square_mm
    if env.square_mm_uncertainty_um is None:
        rows.append(BudgetRow("board square size", "B", None, "\u00b5m", n_squares, None,
                              "not stated (the board's certificate: lps capture --square-u, or the report set-up); not in U"))
    else:
        u = env.square_mm_uncertainty_um
        rows.append(BudgetRow("board square size", "B", u, "\u00b5m", n_squares, n_squares * u,
                              f"certificate of the board; {n_squares:.1f} squares over the travel"))
    alpha, dT = env.board_cte_ppm_per_k, env.board_delta_k
    if alpha is None or dT is None:
        rows.append(BudgetRow("board temperature", "B", None, "K", None, None,
                              "board temperature or expansion coefficient not recorded; no thermal correction, not in U"))
        rows.append(BudgetRow("board expansion coefficient", "B", None, "ppm/K", None, None, "not recorded"))
    else:
        c_t = alpha * L * 1e-3  # um per K
        rows.append(BudgetRow("board temperature", "B", env.temperature_u_k(), "K", c_t, abs(c_t) * env.temperature_u_k(),
                              f"thermometer; correction {alpha * dT:+.1f} ppm applied ({env.board_temperature_c:g} \u00b0C)"))
        c_a = abs(dT) * L * 1e-3  # um per ppm/K
        rows.append(BudgetRow("board expansion coefficient", "B", env.board_cte_u_ppm(), "ppm/K", c_a,
                              c_a * env.board_cte_u_ppm(), f"{alpha:g} ppm/K; uncertainty of the coefficient"))
    a_s, dTs = env.stage_cte_ppm_per_k, env.stage_delta_k
    if a_s is None or dTs is None:
        rows.append(BudgetRow("stage temperature", "B", None, "K", None, None,
                              "stage temperature or expansion coefficient not recorded; not in U"))
    else:
        c_s = a_s * L * 1e-3
        half = abs(dTs)
        rows.append(BudgetRow("stage temperature", "B", half / math.sqrt(3.0), "K", c_s, abs(c_s) * half / math.sqrt(3.0),
                              f"stage at {env.stage_temperature_c:g} \u00b0C, expansion to 20 \u00b0C not corrected "
                              "(rectangular)"))
    rows.append(_abbe_row(x))
    return rows


def _abbe_row(x: BudgetInputs) -> BudgetRow:
    """Abbe term: the tilt along the travel that is not per-view noise, times its lever arm.

    A rotation w = pitch v1 + yaw v2 moves the board point r = d v2 + h v1 (seen
    from the camera) along the motion u by (w x r) . u = pitch d - yaw h: pitch
    acts over the board distance d, yaw over the board's sideways offset h.
    """
    if x.abbe_lever_mm is None or x.tilt_urad is None or x.tilt_sigma_urad is None or not len(x.tilt_urad):
        return BudgetRow(ABBE_SOURCE, "B", None, "\u00b5rad", None, None, "no per-view angles; not in U")
    spread = smooth_tilt_spread_urad(np.asarray(x.tilt_urad, float), np.asarray(x.tilt_sigma_urad, float),
                                     None if x.target_mm is None else np.asarray(x.target_mm, float))
    judged = ""
    if x.tilt_resolved is not None:  # an angle the error motions do not resolve (a lens misfit could fake it) is no term
        spread = np.where(np.asarray(x.tilt_resolved, bool), spread, 0.0)
        judged = "; " + ", ".join(f"{n} {'resolved' if r else 'not resolved: no term'}"
                                  for n, r in zip(("pitch (EBX)", "yaw (ECX)"), x.tilt_resolved))
    lever = np.abs(np.asarray(x.abbe_lever_mm, float))
    contribution = float(np.sqrt(np.sum((1e-3 * lever * spread) ** 2)))  # um
    angle = float(np.sqrt(np.sum(spread**2)))
    c = contribution / angle if angle > 0 else float(lever[0]) * 1e-3
    return BudgetRow(ABBE_SOURCE, "B", angle, "\u00b5rad", c, contribution,
                     f"smooth pitch {spread[0]:.1f} \u00b5rad x {lever[0]:.0f} mm, yaw {spread[1]:.1f} \u00b5rad x "
                     f"{lever[1]:.0f} mm, the camera-board geometry's lever arms (beyond per-view noise){judged}; not in "
                     "U: the positions are at the board plane, this is what the camera centre's would differ by")


def smooth_tilt_spread_urad(tilt: np.ndarray, sigma: np.ndarray, target_mm: np.ndarray | None,
                            degree: int = TILT_DEGREE) -> np.ndarray:
    """RMS spread of pitch and of yaw along the travel that is not per-view noise (urad), shape (2,).

    Per-view angles are noisy (tens of urad) while a carriage tilts smoothly:
    a polynomial of ``degree`` in the target is fitted to each angle, and the
    noise's share of the fitted curve's variance (sigma^2 (degree + 1) / n)
    is subtracted. Without targets, the raw variance minus sigma^2 is used.
    What remains counts only above ``TILT_K`` standard deviations of that
    noise share: a quick demo's per-view sigma of ~500 urad otherwise left a
    random ~80 urad "tilt" (a 50 um Abbe term on a stage with none).
    """
    ok = np.all(np.isfinite(tilt), axis=1)
    tilt, sigma = tilt[ok], sigma[ok]
    n = tilt.shape[0]
    noise = np.nanmedian(sigma, axis=0) ** 2 if sigma.size else np.zeros(tilt.shape[1])
    if target_mm is not None and n > degree + 2 and np.ptp(target_mm[ok]) > 0:
        t = target_mm[ok]
        u = (t - t.mean()) / np.ptp(t)
        A = np.vander(u, degree + 1)
        fit = A @ np.linalg.lstsq(A, tilt, rcond=None)[0]
        spread = np.var(fit, axis=0) - noise * (degree + 1) / n
        scatter = noise * math.sqrt(2.0 * (degree + 1)) / n  # sd of that noise share (chi-square, degree + 1 dof)
    elif n > 1:
        spread = np.var(tilt, axis=0) - noise
        scatter = noise * math.sqrt(2.0 / n)
    else:
        return np.zeros(tilt.shape[1])
    # a tilt curve within TILT_K sd of what noise alone leaves is not resolved: no Abbe term from noise
    spread = np.where(spread > TILT_K * scatter, spread, 0.0)
    return np.sqrt(np.clip(spread, 0.0, None))


def _finite(v: float) -> float | None:
    return float(v) if v is not None and math.isfinite(v) else None


def combine(rows: list[BudgetRow], k: float = COVERAGE_FACTOR) -> dict[str, Any]:
    """results.json ``uncertainty``: the budget, u_c, U (k) and what is not in U."""
    known = [r.contribution_um for r in rows if r.contribution_um is not None and r.source != ABBE_SOURCE]
    u_c = float(np.sqrt(np.sum(np.square(known)))) if known else None
    noise = [r.contribution_um for r in rows if r.source in NOISE_SOURCES and r.contribution_um is not None]
    u_noise = float(np.sqrt(np.sum(np.square(noise)))) if noise else None
    return {
        "budget": [asdict(r) for r in rows],
        "combined_standard_um": u_c,
        "coverage_factor": k,
        "expanded_k2_um": None if u_c is None else k * u_c,
        "noise_standard_um": u_noise,
        "not_in_u": [r.source for r in rows if r.contribution_um is None],
        "applies_to": "a displacement over the measured travel, at the board plane",
    }


def figure_uncertainties(unc: dict[str, Any], figures: dict[str, Any], travel_mm: float,
                         n_views: int = 0, n_targets: int = 0,
                         angle_sigma_urad: dict[str, float] | None = None) -> dict[str, float | None]:
    """U (k = 2) of each headline figure, keyed like the figures (um, ppm for the scale, urad for angles).

    The one source of every U the report, the GUI and the CLI print; the mean
    step's is ``mean_step_um`` (U over the travel / (``n_targets`` - 1)), the
    p-v and max |x| figures' come from :func:`extreme_uncertainties`.

    The periodic amplitude is a sinusoid fitted to ``n_views`` noisy positions:
    its 1-sigma is the per-view noise times sqrt(2 / n) (the reference view's
    noise is a common offset, the scale terms a trend: neither enters). A
    periodic error the plan does not define has no U.
    """
    k = float(unc.get("coverage_factor") or COVERAGE_FACTOR)
    U = unc.get("expanded_k2_um")
    u_noise = unc.get("noise_standard_um")
    at_target = None if u_noise is None else k * math.sqrt(2.0) * u_noise  # two approaches, common terms cancel
    out: dict[str, float | None] = {}
    for key in ("A_um", "A_up_um", "A_down_um", "E_um", "E_up_um", "E_down_um", "M_um", "max_abs_deviation_um",
                "deviation_span_um", "position_um"):
        out[key] = U
    for key in ("R_um", "R_up_um", "R_down_um", "B_um", "B_mean_um", "step_std_um"):
        out[key] = at_target
    out.update(iso_noise_uncertainties(unc, figures, k))
    single = figures.get("single_run") or {}
    scale_u = single.get("scale_sigma_total_ppm")
    if scale_u is not None and travel_mm > 0:
        scale_terms = [r["contribution_um"] for r in unc.get("budget") or []
                       if r["contribution_um"] is not None and r["source"] not in NOISE_SOURCES + ("intrinsics", ABBE_SOURCE)]
        rel = [1e3 * c / travel_mm for c in scale_terms]  # um over L -> ppm
        out["scale_ppm"] = k * math.sqrt(float(scale_u) ** 2 + sum(r * r for r in rel))
    out["periodic_amplitude_um"] = (None if u_noise is None or n_views < 3 or single.get("periodic_amplitude_um") is None
                                    else k * (u_noise / math.sqrt(2.0)) * math.sqrt(2.0 / n_views))  # per-view part
    s = figures.get("straightness_sigma_um")
    out["straightness_um_max"] = None if s is None else k * float(s)
    out.update(extreme_uncertainties(figures, k, angle_sigma_urad or {}))
    if n_targets >= 2 and U is not None:
        out["mean_step_um"] = float(U) / (n_targets - 1)  # (last - first) / (n - 1): U over the travel shared out
    return out


def iso_noise_uncertainties(unc: dict[str, Any], figures: dict[str, Any], k: float) -> dict[str, float]:
    """U (k) of the noise-corrected ISO 230-2 figures (``iso230_2.noise_correction``) and max |deviation|
    (``single_run.max_abs_deviation_noise``), keyed like the figures.

    The Monte Carlo's u replaces the budget's noise rows: spans over the travel (A, E, M) add it to the
    budget's other rows (scale, intrinsics, lens, Abbe: common to a target across runs); differences at
    one target (R, B) take it alone (those terms cancel there).
    """
    corr = dict((figures.get("iso230_2") or {}).get("noise_correction") or {})
    max_dev = (figures.get("single_run") or {}).get("max_abs_deviation_noise")
    if isinstance(max_dev, dict):  # a max over the deviations, corrected alike (core/metrology/extreme_noise.py)
        corr["max_abs_deviation_um"] = max_dev
    rows = [r["contribution_um"] for r in unc.get("budget") or []
            if r.get("contribution_um") is not None and r.get("source") not in NOISE_SOURCES + (ABBE_SOURCE,)]
    u_other2 = float(np.sum(np.square(rows))) if rows else 0.0
    out: dict[str, float] = {}
    for key, c in corr.items():
        u = c.get("u_noise")
        if u is None or not math.isfinite(u):
            continue
        at_target = key.startswith(("R_", "B_"))
        out[key] = k * math.sqrt(u * u + (0.0 if at_target else u_other2))
    return out


def extreme_uncertainties(figures: dict[str, Any], k: float, angle_sigma_urad: dict[str, float]) -> dict[str, float]:
    """U (k) of the peak-to-valley and max |x| figures, keyed like the report's rows (um, urad).

    A p-v or a max |x| is printed with the noise's selection taken out
    (:mod:`lps_gui.core.metrology.extreme_noise`): k times that correction's standard uncertainty
    (``u_span_um``, ``u_max_abs_urad``; a straightness's with ``u_model_um``, the constant-orientation
    model's overstatement of a carriage rotation, in quadrature). Without it (a document written before), a p-v of per-target
    means is the difference of two of them: k sqrt 2 times the sigma of one mean
    (``figures["straightness"]["v1"]["sigma_um"]``), a max |angle| one view's angle: k times the median
    per-view sigma (``angle_sigma_urad``). ``straightness_span_max`` is the U of the larger span, the one
    the straight-line verdict compares with its limit. Whether
    noise alone could give the figure is a separate question
    (:mod:`lps_gui.core.metrology.resolution`): an unresolved figure is printed without a value.
    """
    out: dict[str, float] = {}
    st = figures.get("straightness")
    if isinstance(st, dict):
        spans = []
        for j in (1, 2):
            d = st.get(f"v{j}") or {}
            u_model = float(d.get("u_model_um") or 0.0)  # the model's overstatement of a rotation (board plane)
            if d.get("u_span_um") is not None:
                out[f"straightness_span_{j}"] = k * math.hypot(float(d["u_span_um"]), u_model)
            elif d.get("sigma_um") is not None:
                out[f"straightness_span_{j}"] = k * math.hypot(math.sqrt(2.0) * float(d["sigma_um"]), u_model)
            if f"straightness_span_{j}" in out and d.get("span_um") is not None:
                spans.append((float(d["span_um"]), out[f"straightness_span_{j}"]))
        if spans:
            out["straightness_span_max"] = max(spans)[1]
    rot = figures.get("image_rotation")
    if isinstance(rot, dict) and rot.get("u_span_urad") is not None:
        out["image_rotation_span"] = k * float(rot["u_span_urad"])
    elif isinstance(rot, dict) and rot.get("sigma_urad") is not None:
        out["image_rotation_span"] = k * math.sqrt(2.0) * float(rot["sigma_urad"])
    angles = figures.get("angles_resolution") or {}
    for name, sigma in angle_sigma_urad.items():
        u = (angles.get(name) or {}).get("u_max_abs_urad")
        if u is not None and math.isfinite(u):
            out[f"max_abs_{name}"] = k * float(u)
        elif sigma is not None and math.isfinite(sigma):
            out[f"max_abs_{name}"] = k * float(sigma)
    return out
