"""Plots of the ASME B5.64 tests as plain data (results.json ``asme_b5_64``): steps and settling. No Qt here."""
from __future__ import annotations

import numpy as np

from lps_gui.io.results.sections import AsmeB564, IncrementalStep, Settling
from lps_gui.report.figures.spec import (
    BACKWARD_COLOR,
    FORWARD_COLOR,
    OUTLIER_COLOR,
    SPEC_COLOR,
    TRUTH_COLOR,
    FigureSpec,
    Series,
)

STOP_COLORS = ("#1f5fa8", "#e07b00", "#2a9d3c", "#a8326e", "#6b3500", "#0d2747")


def step_figure(step: IncrementalStep) -> FigureSpec:
    """Each incremental step achieved (+-2 sigma) against its number, beside the command; stuck steps marked."""
    rows = step.steps
    n = np.arange(1, len(rows) + 1, dtype=float)
    achieved = np.array([abs(r.achieved_um) * (1 if r.achieved_um * r.commanded_um >= 0 else -1)
                         for r in rows], dtype=float)
    sigma = np.array([r.sigma_um for r in rows], dtype=float)
    commanded = np.array([abs(r.commanded_um) for r in rows], dtype=float)
    forward = np.array([r.direction == "+" for r in rows], dtype=bool)
    stuck = np.array([r.stuck for r in rows], dtype=bool)
    series = []
    for sel, label, color in ((forward, "forward steps", FORWARD_COLOR), (~forward, "backward steps", BACKWARD_COLOR)):
        if sel.any():
            series.append(Series(n[sel], achieved[sel], f"{label} achieved \u00b1 2\u03c3", "markers", color,
                                 achieved[sel] - 2 * sigma[sel], achieved[sel] + 2 * sigma[sel], stuck[sel],
                                 marked_label="stuck step"))
    series.append(Series(n, commanded, "commanded", "line", TRUTH_COLOR, dashed=True))
    return FigureSpec("min_step", "Incremental steps: achieved against commanded (stops averaged)", "step number",
                      "step along the command [\u00b5m]", series,
                      notes="red crosses: stuck steps (less than half the command, and short of the tolerance by more than 2\u03c3)")


def settling_figure(settling: Settling) -> FigureSpec:
    """Position after each move (relative to rest) against time, the band, and the time to settle."""
    band = float(settling.band_um or 0.0)
    series = []
    t_max = 0.0
    for k, stop in enumerate(settling.stops):
        t = np.asarray(stop.since_move_s, dtype=float)
        x = np.asarray(stop.position_um, dtype=float)
        t_max = max(t_max, float(np.nanmax(t)) if t.size else 0.0)
        arrow = "\u2191" if stop.direction == "+" else "\u2193"
        label = f"{stop.target_mm:g} mm {arrow}"
        series.append(Series(t, x, label, "line+markers" if k == 0 else "line", STOP_COLORS[k % len(STOP_COLORS)]))
    if t_max > 0 and band > 0:
        series.append(Series(np.array([0.0, t_max, np.nan, 0.0, t_max]), np.array([band, band, np.nan, -band, -band]),
                             f"band \u00b1{band:g} \u00b5m", "line", SPEC_COLOR, dashed=True))
    settle = settling.settling_time_s
    if settle is not None and series:
        top = max(float(np.nanmax(np.abs(s.y))) for s in series)
        series.append(Series(np.array([settle, settle]), np.array([-top, top]), f"settled: {settle:.3f} s (fit)",
                             "line", OUTLIER_COLOR))
    return FigureSpec("settling", "Settling: position after each move against time", "time after the move [s]",
                      "position \u2212 rest, along the move [\u00b5m]", series)


def test_figures(section: AsmeB564 | None) -> list[FigureSpec]:
    """The figures of the tests a session ran (steps, settling), in the report's order; [] for none."""
    if section is None:
        return []
    return [step_figure(t) if isinstance(t, IncrementalStep) else settling_figure(t) for t in section.tests_run]
