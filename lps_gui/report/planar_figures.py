"""Plot definitions of a planar (XY) session, shared by the GUI and the PDF (SPEC 10).

The 2-D error map is a quiver plot: at every grid node an arrow from the
target to target + exaggeration x mean error, drawn as line segments (the
plot painter breaks lines at NaN), the exaggeration stated in the title.
Per-axis deviation plots show each line of the plan along its moving axis;
straightness plots the cross-axis deviation about each line's least-squares
line.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.io.results_model import Results, as_results
from lps_gui.report.figure_spec import FORWARD_COLOR, TRUTH_COLOR, FigureSpec, Series

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
