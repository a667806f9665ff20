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

from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from lps_gui.core.metrology.iso230_spectrum import UNDEFINED_TEXT
from lps_gui.io.results.model import Results, as_results
from lps_gui.report.figures.spec import (
    BACKWARD_COLOR,
    COMPONENT_COLORS,
    DIRECTION_ARROWS,
    DIRECTION_NAMES,
    FORWARD_COLOR,
    IMAGE_ROTATION_COLOR,
    SPEC_COLOR,
    TRUTH_COLOR,
    TRUTH_COLORS,
    FigureSpec,
    Series,
)
from lps_gui.report.figures.targets import with_target_stretches
from lps_gui.sim.truth import centred, residual_from_line, true_deviation_um
from lps_gui.io.results.keys import DEVIATION_UM, MEASURED_MM, SIGMA_TOTAL_UM

TRUTH_AT_MEASUREMENT = "truth_plane_deviation_um"  # the true deviation where the positions are measured (sim/truth)
TRUTH_KEYS = (DEVIATION_UM, "straightness_um_1", "straightness_um_2", "roll_urad", "pitch_urad", "yaw_urad",
              "image_rotation_urad")
FIGURE_KEYS = ("positions", "deviation", "step", "straightness", "angles", "residuals", "spectrum")


# ----------------------------------------------------------------------------- table access


def position_columns(results: Results | dict[str, Any] | None) -> dict[str, np.ndarray]:
    """The per-position table of the results as arrays (NaN where absent; no rows without results).

    Returns float arrays (shape (K,)) for every numeric column, ``direction``
    as a str array, ``outlier`` as bool, sorted by capture index.
    """
    results = None if results is None else as_results(results)
    rows = results.sorted_positions() if results is not None else []
    numeric = ("index", "run", "target_mm", MEASURED_MM, DEVIATION_UM, "sigma_um", SIGMA_TOTAL_UM,
               "rms_px", "n_corners", "straightness_um_1", "straightness_um_2", "straightness_sigma_um_1",
               "straightness_sigma_um_2", "roll_urad", "pitch_urad", "yaw_urad", "roll_sigma_urad",
               "pitch_sigma_urad", "yaw_sigma_urad", "image_rotation_urad", "image_rotation_sigma_urad")
    cols: dict[str, np.ndarray] = {}
    for name in numeric:
        cols[name] = results.column(name, rows) if results is not None else np.zeros(0)
    cols["direction"] = np.array([r.direction for r in rows], dtype=object)
    cols["outlier"] = np.array([r.outlier for r in rows], dtype=bool)
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


def truth_columns(results: Results | dict[str, Any] | None, truth: dict[str, Any] | None) -> dict[str, np.ndarray] | None:
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
    if results is None:
        return None
    results = as_results(results)
    rows = results.sorted_positions()
    if rows and any(r.get("truth_deviation_um") is not None for r in rows):
        out = {key: results.column(f"truth_{key}", rows) for key in TRUTH_KEYS}
        plane = results.column(TRUTH_AT_MEASUREMENT, rows)
        if np.isfinite(plane).any():  # like with like: the positions are measured at the board plane (issue 37)
            out[DEVIATION_UM] = plane
        return out
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
    ref_index = results.parameters.reference_index
    ref = int(np.flatnonzero(idx == ref_index)[0]) if ref_index in set(idx.tolist()) else int(np.flatnonzero(compared)[0])
    out: dict[str, np.ndarray] = {DEVIATION_UM: true_deviation_um(s_true_mm[idx], cols["target_mm"], ref)}
    straight = np.asarray(truth.get("straightness_um") or np.zeros((s_true_mm.size, 2)), dtype=float)[idx]
    resid = residual_from_line(straight, cols["target_mm"], compared)  # shape (K, 2): distance from the best line
    out["straightness_um_1"], out["straightness_um_2"] = resid[:, 0], resid[:, 1]
    angles = centred(np.asarray(truth.get("angles_urad") or np.zeros((s_true_mm.size, 3)), dtype=float)[idx], compared)
    out["roll_urad"], out["pitch_urad"], out["yaw_urad"] = angles[:, 0], angles[:, 1], angles[:, 2]
    return out


# ----------------------------------------------------------------------------- figures


def figures_from_results(results: Results | dict[str, Any] | None, truth: dict[str, Any] | None = None
                         ) -> list[FigureSpec]:
    """Every report figure of a results dict, in report order (keys: :data:`FIGURE_KEYS`).

    Parameters
    ----------
    results : Results, optional
        results.json read (a results dict is read into one); None: the empty figures (titles and axes).
    truth : dict, optional
        The session's ``truth`` record (simulated sessions); drawn dashed beside
        the measurement. Without it, a ``truth`` section of the results is used when present.
    """
    results = None if results is None else as_results(results)
    if results is not None and results.planar:  # a planar session (SPEC 10)
        return planar_figures_from_results(results)
    cols = position_columns(results)
    if truth is None and results is not None:
        truth = results.extra.get("truth")
    tcols = truth_columns(results, truth)
    row = results is not None and bool(results.targets)  # a row of targets (SPEC 13): no per-view board-plane figures
    return [
        positions_figure(cols),
        with_target_stretches(deviation_figure(cols, tcols), results),
        step_figure(cols, tcols),
        for_row(straightness_figure(cols, None)) if row else straightness_figure(cols, tcols),
        for_row(angles_figure(cols, None)) if row else angles_figure(cols, tcols),
        residuals_figure(cols),
        spectrum_figure(results),
    ]


def for_row(figure: FigureSpec) -> FigureSpec:
    """A board-plane figure of a session with targets: empty (the row model fits no per-view orientation),
    with a note pointing to the error motions (SPEC 14), which give straightness and angles at the camera."""
    return replace(figure, series=[], notes="a row of targets: the model fits one camera orientation and no per-view "
                   "offsets, so straightness and angles come from the error motions (the error motions page)")


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
        series.append(Series(cols["target_mm"][sel], cols[MEASURED_MM][sel], f"measured {_dir_label(d)}",
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
        x, y = cols["target_mm"][sel], cols[DEVIATION_UM][sel]
        t, mean, std, count = per_target_stats(x, y, keep[sel])
        if count.size and count.max() > 1:
            runs = np.unique(cols["run"][sel][np.isfinite(cols["run"][sel])]).size if "run" in cols else 0
            what = "runs" if runs >= count.max() else "captures"  # repeated stops of one run are not runs (issue 37)
            series.append(Series(x, y, f"{what} {_dir_label(d)}", "markers", _color(d), marked=cols["outlier"][sel]))
            band = 2.0 * np.nan_to_num(std)
            series.append(Series(t, mean, f"mean \u00b12s {_dir_label(d)}", "line", _color(d),
                                 band_low=mean - band, band_high=mean + band))
            notes.append(f"{_dir_label(d)}: band = mean \u00b1 2 s over {int(count.max())} runs" if what == "runs" else
                         f"{_dir_label(d)}: band = mean \u00b1 2 s over up to {int(count.max())} captures per target "
                         f"({runs} run{'s' if runs != 1 else ''})")
        else:
            sig = 2.0 * np.nan_to_num(drawn_sigma_um(cols)[sel])
            series.append(Series(x, y, f"deviation {_dir_label(d)}", "line+markers", _color(d),
                                 band_low=y - sig, band_high=y + sig, marked=cols["outlier"][sel]))
            notes.append(f"{_dir_label(d)}: band = \u00b12 sigma (noise, intrinsics, lens model)")
        if tcols is not None:
            tt, tmean, _, _ = per_target_stats(x, tcols[DEVIATION_UM][sel], np.ones(x.shape, bool))
            series.append(_truth_series(tt, tmean, f"truth {_dir_label(d)}", TRUTH_COLORS[d]))
    return FigureSpec("deviation", "Positioning deviation vs target", "target position [mm]", "deviation [\u00b5m]",
                      series, "; ".join(notes))


def drawn_sigma_um(cols: dict[str, np.ndarray]) -> np.ndarray:
    """The per-stop sigma the bands draw: ``sigma_total_um`` (noise, the intrinsics' covariance, the lens misfit
    where estimated), ``sigma_um`` where a source has no total. Why: the intrinsics and the lens misfit are common
    to neighbouring stops and do not average out; a band of the noise alone missed the truth by 3-12 sigma on
    two-depth constellations (issue 35, docs/validation.md)."""
    noise = np.asarray(cols["sigma_um"], dtype=float)
    total = cols.get(SIGMA_TOTAL_UM)
    return noise if total is None else np.where(np.isfinite(total), total, noise)


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
    truth_steps = dict((d, (x, y)) for d, x, y in step_deviation(cols, tcols[DEVIATION_UM])) if tcols else {}
    for d, x, y in step_deviation(cols, cols[DEVIATION_UM]):
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


def spectrum_figure(results: Results | dict[str, Any] | None) -> FigureSpec:
    """Amplitude spectrum of the deviation: a lead-screw pitch shows as a peak."""
    single = as_results(results).figures.single_run if results is not None else None
    spec = single.spectrum if single else None
    period = np.asarray(spec.period_mm if spec else [], dtype=float)
    amp = np.asarray(spec.amplitude_um if spec else [], dtype=float)
    order = np.argsort(period)
    series = [Series(period[order], amp[order], "amplitude", "line+markers", FORWARD_COLOR)] if period.size else []
    notes = ""
    if single and single.periodic_period_mm:
        notes = (f"strongest period {single.periodic_period_mm:.3g} mm, "
                 f"amplitude {single.periodic_amplitude_um or 0:.3g} \u00b5m")
    elif single and single.max_abs_deviation_um is not None:  # captures, but no period the plan resolves
        notes = f"periodic error {UNDEFINED_TEXT}"
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


# ----------------------------------------------------------------------------- planar pages (SPEC 10)
# The 2-D error map is a quiver plot: at every grid node an arrow from the target to target + exaggeration x
# mean error, drawn as line segments (the plot painter breaks lines at NaN), the exaggeration stated in the
# title. Per-axis deviation plots show each line of the plan along its moving axis; straightness plots the
# cross-axis deviation about each line's least-squares line.

PLANAR_FIGURE_KEYS = ("error_map", "deviation_x", "deviation_y", "straightness_x", "straightness_y", "residuals")
LINE_COLORS = ("#1f5fbf", "#d4600a", "#2a9d3a", "#8e3bb5", "#b8860b", "#17a2b8", "#c0392b", "#555555")
ARROW_FRACTION = 0.8  # the longest arrow spans this fraction of the grid step


def planar_columns(results: Results | dict[str, Any]) -> dict[str, np.ndarray]:
    """The planar per-position table as arrays, sorted by capture index."""
    results = as_results(results)
    rows = results.sorted_positions()
    names = ("index", "run", "target_x_mm", "target_y_mm", "deviation_x_um", "deviation_y_um", "sigma_x_um",
             "sigma_y_um", "rms_px", "truth_deviation_x_um", "truth_deviation_y_um")
    cols = {n: results.column(n, rows) for n in names}
    cols["direction"] = np.array([r.direction for r in rows], dtype=object)
    cols["outlier"] = np.array([r.outlier for r in rows], dtype=bool)
    return cols


def nice_exaggeration(longest_um: float, step_mm: float) -> float:
    """A round factor (1, 2, 5 x 10^k) that draws the longest error as ~ARROW_FRACTION of a grid step."""
    if not (longest_um > 0 and step_mm > 0):
        return 1.0
    raw = ARROW_FRACTION * step_mm * 1e3 / longest_um
    k = np.floor(np.log10(raw))
    for m in (5.0, 2.0, 1.0):
        if m * 10**k <= raw:
            return float(m * 10**k)
    return float(10**k)


def error_map_figure(results: Results | dict[str, Any]) -> FigureSpec:
    """Mean 2-D error vector at every grid node, exaggerated (scale in the title)."""
    planar = as_results(results).figures.planar
    nodes = planar.nodes if planar else ()
    have = [n for n in nodes if n.error_um]
    if not have:
        return FigureSpec("error_map", "2-D error map", "X target [mm]", "Y target [mm]", [])
    t = np.array([n.target_mm for n in have], dtype=float)  # shape (m, 2)
    e = np.array([n.error_um for n in have], dtype=float)  # shape (m, 2) um
    steps = [np.min(np.diff(np.unique(t[:, a]))) for a in range(2) if np.unique(t[:, a]).size > 1]
    step = float(min(steps)) if steps else 1.0
    longest = float(np.max(np.hypot(e[:, 0], e[:, 1])))
    k = nice_exaggeration(longest, step)
    tip = t + k * e * 1e-3
    x = np.column_stack([t[:, 0], tip[:, 0], np.full(len(t), np.nan)]).ravel()
    y = np.column_stack([t[:, 1], tip[:, 1], np.full(len(t), np.nan)]).ravel()
    series = [Series(t[:, 0], t[:, 1], "grid node (target)", "markers", "#777777"),
              Series(x, y, "mean error", "line", FORWARD_COLOR)]
    truth = [n for n in nodes if n.truth_error_um]
    if truth:
        tt = np.array([n.target_mm for n in truth], float)
        te = np.array([n.truth_error_um for n in truth], float)
        ttip = tt + k * te * 1e-3
        series.append(Series(np.column_stack([tt[:, 0], ttip[:, 0], np.full(len(tt), np.nan)]).ravel(),
                             np.column_stack([tt[:, 1], ttip[:, 1], np.full(len(tt), np.nan)]).ravel(),
                             "truth (simulation)", "line", TRUTH_COLOR, dashed=True))
    scale_um = step * 1e3 / k
    title = f"2-D error map: vectors x{k:g} (one grid step {step:g} mm = {scale_um:.3g} \u00b5m of error)"
    return FigureSpec("error_map", title, "X target [mm]", "Y target [mm]", series,
                      f"longest mean error {longest:.2f} \u00b5m; arrows from each target to target + {k:g} x error")


def _line_series(cols: dict[str, np.ndarray], moving: int, value: str, detrend: bool) -> list[Series]:
    """One series per line of the plan along ``moving`` (0: X, 1: Y): the mean at each target over runs and passes."""
    other = 1 - moving
    t_move = cols["target_x_mm" if moving == 0 else "target_y_mm"]
    t_other = cols["target_y_mm" if moving == 0 else "target_x_mm"]
    v = cols[value]
    keep = ~cols["outlier"] & np.isfinite(v)
    series = []
    levels = np.unique(np.round(t_other[keep], 6))
    for j, level in enumerate(levels):
        sel = keep & (np.abs(t_other - level) < 1e-6)
        if np.unique(t_move[sel]).size < 3:
            continue
        x, inv = np.unique(np.round(t_move[sel], 6), return_inverse=True)
        y = np.bincount(inv.ravel(), v[sel]) / np.bincount(inv.ravel())  # mean over runs and directions
        if detrend:
            A = np.column_stack([np.ones(x.size), x - x.mean()])
            y = y - A @ np.linalg.lstsq(A, y, rcond=None)[0]
        name = ("Y" if moving == 0 else "X") + f" = {level:g} mm"
        series.append(Series(x, y, name, "line+markers", LINE_COLORS[j % len(LINE_COLORS)]))
    del other
    return series


def deviation_axis_figure(cols: dict[str, np.ndarray], moving: int) -> FigureSpec:
    axis = "XY"[moving]
    series = _line_series(cols, moving, f"deviation_{axis.lower()}_um", detrend=False)
    return FigureSpec(f"deviation_{axis.lower()}", f"{axis} positioning deviation along each {axis} line",
                      f"{axis} target [mm]", f"{axis} deviation [\u00b5m]", series,
                      "mean over runs and passes per target; offset zero at the first capture")


def straightness_planar_figure(cols: dict[str, np.ndarray], moving: int) -> FigureSpec:
    """Cross-axis deviation of every line along ``moving`` about its least-squares line (ISO 230-1)."""
    axis, other = "XY"[moving], "YX"[moving]
    series = _line_series(cols, moving, f"deviation_{other.lower()}_um", detrend=True)
    return FigureSpec(f"straightness_{axis.lower()}", f"Straightness of {axis}: {other} deviation along each {axis} line",
                      f"{axis} target [mm]", f"{other} straightness [\u00b5m]", series,
                      "about each line's least-squares line; mean over runs and passes")


def planar_residuals_figure(cols: dict[str, np.ndarray]) -> FigureSpec:
    series = [Series(cols["index"], cols["rms_px"], "RMS reprojection per view", "markers", FORWARD_COLOR,
                     marked=cols["outlier"])]
    return FigureSpec("residuals", "Reprojection error per view", "capture index", "RMS [px]", series)


def planar_figures_from_results(results: Results | dict[str, Any]) -> list[FigureSpec]:
    """Every figure of a planar session, in report order (keys: :data:`PLANAR_FIGURE_KEYS`)."""
    results = as_results(results)
    cols = planar_columns(results)
    return [error_map_figure(results), deviation_axis_figure(cols, 0), deviation_axis_figure(cols, 1),
            straightness_planar_figure(cols, 0), straightness_planar_figure(cols, 1), planar_residuals_figure(cols)]
