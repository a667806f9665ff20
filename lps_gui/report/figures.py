"""Plot definitions as plain data, shared by the GUI (pyqtgraph) and the PDF (QPainter).

A :class:`FigureSpec` says what to draw, never how: axis labels with units,
series of (x, y) with a style and a colour, optional 2-sigma bands and marked
outliers. :func:`figures_from_results` builds every figure of a report from a
results dict (results.json content, see docs/ARCHITECTURE.md), so the screen
and the paper show the same numbers. No Qt here.

Truth (simulated sessions only) is drawn beside the measurement, dashed, when
the session's ``truth`` record is given: measured straightness and angles are
relative to the fitted line and mean orientation, so the truth is reduced the
same way (linear trend / mean removed) before it is drawn.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from lps_gui.report.figure_spec import (BACKWARD_COLOR, COMPONENT_COLORS, DIRECTION_ARROWS, DIRECTION_NAMES,
                                        FORWARD_COLOR, IMAGE_ROTATION_COLOR, SPEC_COLOR, TRUTH_COLOR,
                                        TRUTH_COLORS, FigureSpec, Series, num_or_nan)
from lps_gui.report.planar_figures import planar_figures_from_results
from lps_gui.report.target_figures import with_target_stretches
from lps_gui.sim.truth import centred, residual_from_line, true_deviation_um


TRUTH_KEYS = ("deviation_um", "straightness_um_1", "straightness_um_2", "roll_urad", "pitch_urad", "yaw_urad",
              "image_rotation_urad")
FIGURE_KEYS = ("positions", "deviation", "step", "straightness", "angles", "residuals", "spectrum")


# ----------------------------------------------------------------------------- table access


def position_columns(results: dict[str, Any]) -> dict[str, np.ndarray]:
    """The per-position table of a results dict as arrays (NaN where absent).

    Returns float arrays (shape (K,)) for every numeric column, ``direction``
    as a str array, ``outlier`` as bool, sorted by capture index.
    """
    rows = sorted(results.get("positions") or [], key=lambda r: r.get("index", 0))
    numeric = ("index", "run", "target_mm", "measured_mm", "deviation_um", "sigma_um", "sigma_total_um",
               "rms_px", "n_corners", "straightness_um_1", "straightness_um_2", "straightness_sigma_um_1",
               "straightness_sigma_um_2", "roll_urad", "pitch_urad", "yaw_urad", "roll_sigma_urad",
               "pitch_sigma_urad", "yaw_sigma_urad", "image_rotation_urad", "image_rotation_sigma_urad")
    cols: dict[str, np.ndarray] = {}
    for name in numeric:
        cols[name] = np.array([num_or_nan(r.get(name)) for r in rows], dtype=float)
    cols["direction"] = np.array([str(r.get("direction", "+")) for r in rows], dtype=object)
    cols["outlier"] = np.array([bool(r.get("outlier", False)) for r in rows], dtype=bool)
    return cols




def directions_present(cols: dict[str, np.ndarray]) -> list[str]:
    return [d for d in ("+", "-") if (cols["direction"] == d).any()]


def per_target_stats(target_mm: np.ndarray, value: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mean and sample std of ``value`` per distinct target (ISO 230-2 x̄_j, s_j).

    Returns (targets shape (m,), mean (m,), std (m,) NaN with one run, count (m,)).
    Only entries with ``keep`` true and a finite value count.
    """
    ok = keep & np.isfinite(value) & np.isfinite(target_mm)
    targets = np.unique(np.round(target_mm[ok], 9))
    if targets.size == 0:
        empty = np.zeros(0)
        return empty, empty, empty, empty
    idx = np.searchsorted(targets, np.round(target_mm[ok], 9))
    v = value[ok]
    count = np.bincount(idx, minlength=targets.size).astype(float)
    mean = np.bincount(idx, weights=v, minlength=targets.size) / count
    sq = np.bincount(idx, weights=(v - mean[idx]) ** 2, minlength=targets.size)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(count > 1, np.sqrt(sq / np.maximum(count - 1, 1)), np.nan)
    return targets, mean, std, count


# ----------------------------------------------------------------------------- truth


def truth_columns(results: dict[str, Any], truth: dict[str, Any] | None) -> dict[str, np.ndarray] | None:
    """Truth per capture, reduced like the measurement; None for a real session.

    The estimator puts truth beside each position (``truth_deviation_um``,
    ``truth_straightness_um_1`` ..., reduced by :func:`lps_gui.sim.truth.truth_comparison`);
    those are used first. Otherwise ``truth`` is the session's truth record
    (``positions_mm``, ``straightness_um`` (K, 2), ``angles_urad`` (K, 3)) indexed
    by capture index, reduced with the same functions and the same reference
    capture (results' ``reference_index``, else the first capture not flagged).
    Returns arrays aligned with :func:`position_columns`: ``deviation_um``
    (zero at the reference capture), ``straightness_um_1/2`` (linear trend
    removed), ``roll/pitch/yaw_urad`` (mean removed).
    """
    rows = sorted(results.get("positions") or [], key=lambda r: r.get("index", 0))
    if rows and any(r.get("truth_deviation_um") is not None for r in rows):
        return {key: np.array([num_or_nan(r.get(f"truth_{key}")) for r in rows], dtype=float) for key in TRUTH_KEYS}
    if not truth or "positions_mm" not in truth:
        return None
    cols = position_columns(results)
    idx = cols["index"].astype(int)
    s_true_mm = np.asarray(truth["positions_mm"], dtype=float)
    if idx.size == 0 or idx.max() >= s_true_mm.size or idx.min() < 0:
        return None
    compared = ~cols["outlier"]
    if not compared.any():
        return None
    ref_index = (results.get("parameters") or {}).get("reference_index")
    ref = int(np.flatnonzero(idx == ref_index)[0]) if ref_index in set(idx.tolist()) else int(np.flatnonzero(compared)[0])
    out: dict[str, np.ndarray] = {"deviation_um": true_deviation_um(s_true_mm[idx], cols["target_mm"], ref)}
    straight = np.asarray(truth.get("straightness_um") or np.zeros((s_true_mm.size, 2)), dtype=float)[idx]
    resid = residual_from_line(straight, cols["target_mm"], compared)  # shape (K, 2): distance from the best line
    out["straightness_um_1"], out["straightness_um_2"] = resid[:, 0], resid[:, 1]
    angles = centred(np.asarray(truth.get("angles_urad") or np.zeros((s_true_mm.size, 3)), dtype=float)[idx], compared)
    out["roll_urad"], out["pitch_urad"], out["yaw_urad"] = angles[:, 0], angles[:, 1], angles[:, 2]
    return out


# ----------------------------------------------------------------------------- figures


def figures_from_results(results: dict[str, Any], truth: dict[str, Any] | None = None) -> list[FigureSpec]:
    """Every report figure of a results dict, in report order (keys: :data:`FIGURE_KEYS`).

    Parameters
    ----------
    results : dict
        results.json content.
    truth : dict, optional
        The session's ``truth`` record (simulated sessions); drawn dashed beside
        the measurement. Without it, ``results["truth"]`` is used when present.
    """
    if len(results.get("axes") or ["X"]) == 2:  # a planar session (SPEC 10)
        return planar_figures_from_results(results)
    cols = position_columns(results)
    truth = truth if truth is not None else results.get("truth")
    tcols = truth_columns(results, truth)
    return [
        positions_figure(cols),
        with_target_stretches(deviation_figure(cols, tcols), results),  # a row's targets (SPEC 13)
        step_figure(cols, tcols),
        straightness_figure(cols, tcols),
        angles_figure(cols, tcols),
        residuals_figure(cols),
        spectrum_figure(results),
    ]


def _by_direction(cols: dict[str, np.ndarray]) -> list[tuple[str, np.ndarray]]:
    return [(d, cols["direction"] == d) for d in directions_present(cols)]


def _color(direction: str) -> str:
    return FORWARD_COLOR if direction == "+" else BACKWARD_COLOR


def _dir_label(direction: str) -> str:
    return f"{DIRECTION_NAMES[direction]} {DIRECTION_ARROWS[direction]}"


def positions_figure(cols: dict[str, np.ndarray]) -> FigureSpec:
    """Measured position d_i against its target: the line every other plot magnifies."""
    series = []
    for d, sel in _by_direction(cols):
        series.append(Series(cols["target_mm"][sel], cols["measured_mm"][sel], f"measured {_dir_label(d)}",
                             "markers", _color(d), marked=cols["outlier"][sel]))
    return FigureSpec("positions", "Measured position vs target", "target position [mm]", "measured position d\u1d62 [mm]",
                      series)


def deviation_figure(cols: dict[str, np.ndarray], tcols: dict[str, np.ndarray] | None) -> FigureSpec:
    """Deviation vs target per direction, mean with a 2-sigma band.

    With two or more runs the band is the ISO 230-2 x̄_j +- 2 s_j over runs;
    with one run it is the measurement's own +-2 sigma per position.
    """
    series: list[Series] = []
    notes = []
    keep = ~cols["outlier"]
    for d, sel in _by_direction(cols):
        x, y = cols["target_mm"][sel], cols["deviation_um"][sel]
        t, mean, std, count = per_target_stats(x, y, keep[sel])
        if count.size and count.max() > 1:
            series.append(Series(x, y, f"runs {_dir_label(d)}", "markers", _color(d), marked=cols["outlier"][sel]))
            band = 2.0 * np.nan_to_num(std)
            series.append(Series(t, mean, f"mean \u00b12s {_dir_label(d)}", "line", _color(d),
                                 band_low=mean - band, band_high=mean + band))
            notes.append(f"{_dir_label(d)}: band = mean \u00b1 2 s over {int(count.max())} runs")
        else:
            sig = 2.0 * np.nan_to_num(cols["sigma_um"][sel])
            series.append(Series(x, y, f"deviation {_dir_label(d)}", "line+markers", _color(d),
                                 band_low=y - sig, band_high=y + sig, marked=cols["outlier"][sel]))
            notes.append(f"{_dir_label(d)}: band = \u00b12 sigma (measurement noise)")
        if tcols is not None:
            tt, tmean, _, _ = per_target_stats(x, tcols["deviation_um"][sel], np.ones(x.shape, bool))
            series.append(_truth_series(tt, tmean, f"truth {_dir_label(d)}", TRUTH_COLORS[d]))
    return FigureSpec("deviation", "Positioning deviation vs target", "target position [mm]", "deviation [\u00b5m]",
                      series, "; ".join(notes))


def _truth_series(x: np.ndarray, y: np.ndarray, label: str, color: str = TRUTH_COLOR) -> Series:
    order = np.argsort(x, kind="stable")
    return Series(x[order], y[order], label, "line", color, dashed=True)


def _runs(cols: dict[str, np.ndarray]) -> list[np.ndarray]:
    """Index arrays of each (run, direction) in capture order."""
    out = []
    for run in np.unique(cols["run"][np.isfinite(cols["run"])]):
        for d in ("+", "-"):
            sel = np.flatnonzero((cols["run"] == run) & (cols["direction"] == d))
            if sel.size > 1:
                out.append(sel)
    return out


def step_deviation(cols: dict[str, np.ndarray], deviation_um: np.ndarray) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Step deviation (measured step - commanded step, um) within each run, per direction.

    Returns [(direction, mid-target mm shape (k,), step deviation um shape (k,))].
    A step touching an outlier is NaN so it is not drawn.
    """
    out: dict[str, tuple[list, list]] = {}
    for sel in _runs(cols):
        d = cols["direction"][sel[0]]
        step = np.diff(deviation_um[sel])
        bad = cols["outlier"][sel][1:] | cols["outlier"][sel][:-1]
        step = np.where(bad, np.nan, step)
        mid = 0.5 * (cols["target_mm"][sel][1:] + cols["target_mm"][sel][:-1])
        xs, ys = out.setdefault(d, ([], []))
        xs.append(mid)
        ys.append(step)
    return [(d, np.concatenate(xs), np.concatenate(ys)) for d, (xs, ys) in out.items()]


def step_figure(cols: dict[str, np.ndarray], tcols: dict[str, np.ndarray] | None) -> FigureSpec:
    """How much each step differs from the commanded step: the lead-screw signature."""
    series = []
    truth_steps = dict((d, (x, y)) for d, x, y in step_deviation(cols, tcols["deviation_um"])) if tcols else {}
    for d, x, y in step_deviation(cols, cols["deviation_um"]):
        t, mean, _, count = per_target_stats(x, y, np.ones(x.shape, bool))
        label = f"step {_dir_label(d)}" + (" (mean over runs)" if count.size and count.max() > 1 else "")
        series.append(Series(t, mean, label, "markers" if t.size > 150 else "line+markers", _color(d)))
        if d in truth_steps:
            tx, ty = truth_steps[d]
            tt, tmean, _, _ = per_target_stats(tx, ty, np.ones(tx.shape, bool))
            series.append(_truth_series(tt, tmean, f"truth {_dir_label(d)}", TRUTH_COLORS[d]))
    return FigureSpec("step", "Step deviation", "target position (step midpoint) [mm]",
                      "measured step \u2212 commanded step [\u00b5m]", series)


def _component_series(cols: dict[str, np.ndarray], tcols: dict[str, np.ndarray] | None, column: str,
                      sigma_column: str, name: str, color: str) -> list[Series]:
    """Per-target mean over runs of one column, forward as a line and backward as markers, plus truth.

    The forward line carries a +-2 sigma band: the per-view sigma of the mean
    over runs, sqrt(mean sigma^2 / n).
    """
    series = []
    keep = ~cols["outlier"]
    for d, sel in _by_direction(cols):
        t, mean, _, count = per_target_stats(cols["target_mm"][sel], cols[column][sel], keep[sel])
        lo = hi = None
        if d == "+" and np.isfinite(cols[sigma_column][sel]).any():
            _, var, _, _ = per_target_stats(cols["target_mm"][sel], cols[sigma_column][sel] ** 2,
                                            keep[sel] & np.isfinite(cols[column][sel]))
            band = 2.0 * np.sqrt(var / np.maximum(count, 1)) if var.shape == mean.shape else np.zeros_like(mean)
            lo, hi = mean - band, mean + band
        series.append(Series(t, mean, f"{name} {_dir_label(d)}", "line" if d == "+" else "markers", color,
                             band_low=lo, band_high=hi))
    if tcols is not None and column in tcols:
        t, mean, _, _ = per_target_stats(cols["target_mm"], tcols[column], np.ones(keep.shape, bool))
        series.append(_truth_series(t, mean, f"truth {name}", color))
    return series


def straightness_figure(cols: dict[str, np.ndarray], tcols: dict[str, np.ndarray] | None) -> FigureSpec:
    """Distance of the camera centre from the fitted line, in the two perpendicular directions."""
    series = []
    for k in (1, 2):
        series += _component_series(cols, tcols, f"straightness_um_{k}", f"straightness_sigma_um_{k}", f"v{k}",
                                    COMPONENT_COLORS[k - 1])
    return FigureSpec("straightness", "Straightness at the board plane (deviation from the fitted line)", "target position [mm]",
                      "straightness [\u00b5m]", series,
                      "v1: perpendicular closest to the image y axis; v2: along the viewing direction; "
                      "band: \u00b12\u03c3 forward")


def angles_figure(cols: dict[str, np.ndarray], tcols: dict[str, np.ndarray] | None) -> FigureSpec:
    """Roll, pitch and yaw of the camera relative to its mean orientation."""
    series = []
    for k, name in enumerate(("roll", "pitch", "yaw")):
        series += _component_series(cols, tcols, f"{name}_urad", f"{name}_sigma_urad", name, COMPONENT_COLORS[k])
    note = "roll about the motion axis u, pitch about v1, yaw about v2; band: \u00b12\u03c3 forward"
    if np.isfinite(cols["image_rotation_urad"]).any():  # constant-orientation fit (SPEC 11): resolved per view
        series += _component_series(cols, tcols, "image_rotation_urad", "image_rotation_sigma_urad",
                                    "image rotation", IMAGE_ROTATION_COLOR)
        note = "per-view poses: roll about u, pitch about v1, yaw about v2; image rotation: about the optical axis; band \u00b12\u03c3 fwd"
    return FigureSpec("angles", "Angular error motions (roll, pitch, yaw) and image rotation", "target position [mm]",
                      "angle [\u00b5rad]", series, note)


def residuals_figure(cols: dict[str, np.ndarray]) -> FigureSpec:
    """RMS reprojection residual of each view; flagged views marked."""
    series = [Series(cols["index"], cols["rms_px"], "RMS residual", "markers", FORWARD_COLOR, marked=cols["outlier"])]
    n_out = int(cols["outlier"].sum())
    return FigureSpec("residuals", "RMS reprojection residual per view", "capture index [#]", "RMS residual [px]", series,
                      f"{n_out} view(s) flagged as outliers (red crosses)" if n_out else "no view flagged")


def spectrum_figure(results: dict[str, Any]) -> FigureSpec:
    """Amplitude spectrum of the deviation: a lead-screw pitch shows as a peak."""
    single = ((results.get("figures") or {}).get("single_run") or {})
    spec = single.get("spectrum") or {}
    period = np.asarray(spec.get("period_mm") or [], dtype=float)
    amp = np.asarray(spec.get("amplitude_um") or [], dtype=float)
    order = np.argsort(period)
    series = [Series(period[order], amp[order], "amplitude", "line+markers", FORWARD_COLOR)] if period.size else []
    notes = ""
    if single.get("periodic_period_mm"):
        notes = (f"strongest period {float(single['periodic_period_mm']):.3g} mm, "
                 f"amplitude {float(single.get('periodic_amplitude_um') or 0):.3g} \u00b5m")
    return FigureSpec("spectrum", "Error spectrum of the deviation", "period [mm]", "amplitude [\u00b5m]", series,
                      notes, x_log=True)


def figure_by_key(figures: Sequence[FigureSpec], key: str) -> FigureSpec:
    for f in figures:
        if f.key == key:
            return f
    raise KeyError(key)


def with_spec_band(figure: FigureSpec, limit_um: float, plus_minus: bool = True) -> FigureSpec:
    """The deviation figure with the accuracy limit drawn as two dashed red lines.

    The deviation's zero (the first capture) is arbitrary, so the band is
    centred on the measured band (mean +- 2 s, or the deviations), as the
    verdict compares A/2 with a +- limit; a ``"band"`` limit is a full width.
    """
    measured = [s for s in figure.series if not s.dashed]
    lows = [s.band_low if s.band_low is not None else s.y for s in measured]
    highs = [s.band_high if s.band_high is not None else s.y for s in measured]
    lo = np.concatenate([np.ravel(a) for a in lows]) if lows else np.array([])
    hi = np.concatenate([np.ravel(a) for a in highs]) if highs else np.array([])
    lo, hi = lo[np.isfinite(lo)], hi[np.isfinite(hi)]
    xs = np.concatenate([np.ravel(s.x) for s in measured]) if measured else np.array([])
    xs = xs[np.isfinite(xs)]
    if not (lo.size and hi.size and xs.size and np.isfinite(limit_um)):
        return figure
    centre = 0.5 * (float(hi.max()) + float(lo.min()))
    half = float(limit_um) if plus_minus else 0.5 * float(limit_um)
    x0, x1 = float(xs.min()), float(xs.max())
    band = Series(np.array([x0, x1, np.nan, x0, x1]), np.array([centre + half] * 2 + [np.nan] + [centre - half] * 2),
                  f"accuracy limit \u00b1{half:g} \u00b5m (centred on the band)", "line", SPEC_COLOR, dashed=True)
    return FigureSpec(figure.key, figure.title, figure.x_label, figure.y_label, [*figure.series, band],
                      figure.notes, figure.x_log)
