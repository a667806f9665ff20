"""The error-motions page (SPEC 14): the six ISO 230-1 error motions of the axis per stop, and the tool point.

Built from results.json ``error_motions`` (:mod:`lps_gui.pipeline.results.error_motions`):
the three angular motions in one figure and the three linear ones in another,
each curve with its +-2 sigma band (relative to the first stop, as the values
and positions.csv are) and labelled "not resolved" by the profile rule of
:mod:`lps_gui.core.metrology.resolution`; the simulator's truth dashed in the curve's colour; a table of the
profiles; the positioning error at the user's tool point (the Abbe effect).
The figures are plain :class:`FigureSpec` data, so the GUI can draw them too.
No Qt here.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lps_gui.core.metrology.resolution import not_resolved_text
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import ErrorMotions, Motion
from lps_gui.report.figures.spec import COMPONENT_COLORS, FigureSpec, Series, num_or_nan
from lps_gui.report.pages.content import SectionContent

MU = "\u00b5"
LINEAR = ("EXX", "EYX", "EZX")
ANGULAR = ("EAX", "EBX", "ECX")
ROTATION_AXES = {"A": "X", "B": "Y", "C": "Z"}


def what(iso: str) -> str:
    """Words for an ISO 230-1 name E<motion><axis>: EXX positioning, EYX straightness along Y, EAX roll (about X)."""
    motion, axis = iso[1], iso[2]
    if motion == axis:
        return "positioning"
    if motion in "XYZ":
        return f"straightness along {motion}"
    about = ROTATION_AXES[motion]
    if about == axis:
        return f"roll (about {about})"
    return f"{'yaw' if about == 'Z' else 'pitch'} (about {about})"
UNRESOLVED_COLOR = "#9a9a9a"
MOTION_HEADER = ["motion", "what", "p-v", "noise p-v", "median \u03c3", "unit", ""]  # the table, on paper and screen
UNRESOLVED_ROW = "#888888"  # a table row not resolved reads grey, never as a finding


def _axes(section: ErrorMotions) -> list[tuple[str, tuple[str, ...], tuple[str, ...]]]:
    """Per axis, its linear and angular ISO names in SPEC 14's order (X: EXX EYX EZX | EAX EBX ECX)."""
    names = list(section.motions)
    return [(a, tuple(names[6 * k: 6 * k + 3]), tuple(names[6 * k + 3: 6 * k + 6]))
            for k, a in enumerate(section.axis_names)]


def _array(values: Any) -> np.ndarray:
    return np.array([num_or_nan(v) for v in values or []], dtype=float)


def _label(iso: str, m: Motion, resolved: bool) -> str:
    words = f"{iso} {what(iso)}"
    if resolved:
        return words
    unit = f"{MU}m" if m.unit == "um" else f"{MU}rad"
    return f"{words}: {not_resolved_text(m.noise_span(), unit)}"


def _stops(results: Results) -> np.ndarray:
    """The target of every position, mm, in file order."""
    return results.column("target_mm")


def _figure(results: Results, names: tuple[str, ...], key: str, title: str, unit: str) -> FigureSpec:
    section = results.error_motions
    stops = _stops(results)
    series = []
    for k, iso in enumerate(names):
        m = section.motions[iso]
        x = _array(m.positions_mm) if m.positions_mm is not None else stops  # a plane's: over its own axis
        resolved = section.is_resolved(iso)
        y, s = _array(m.values), _array(m.sigma)
        color = COMPONENT_COLORS[k] if resolved else UNRESOLVED_COLOR
        series.append(Series(x, y, _label(iso, m, resolved), "line", color, y - 2 * s, y + 2 * s))
        if iso in section.truth:
            series.append(Series(x, _array(section.truth[iso].true_values), f"truth {iso}", "line", color,
                                 dashed=True))
    frame = ("X, Y in the plane of motion, Z = X \u00d7 Y" if section.axes else
             "X along the motion, Z towards the targets, Y = Z \u00d7 X")
    note = f"relative to the first stop; band \u00b12\u03c3; stage frame: {frame}; grey: not resolved"
    return FigureSpec(key, title, "target position [mm]", f"[{unit}]", series, note)


def error_motion_figures(results: Results | Mapping[str, Any]) -> list[FigureSpec]:
    """The angular and linear error-motion figures, and the tool point's positioning error (when given)."""
    results = as_results(results)
    section = results.error_motions
    if section is None or not section.motions:
        return []
    figures = []
    for axis, linear, angular in _axes(section):
        suffix = "" if axis == "X" else f"_{axis.lower()}"
        figures += [_figure(results, angular, f"error_motions_angular{suffix}", f"Angular error motions of {axis}: "
                            + ", ".join(angular), f"{MU}rad"),
                    _figure(results, linear, f"error_motions_linear{suffix}", f"Linear error motions of {axis}: "
                            + ", ".join(linear), f"{MU}m")]
    linear = _axes(section)[0][1]
    tool = section.tool_point
    if tool:
        x = _stops(results)
        y, s = _array(tool.positioning_um), _array(tool.sigma_um)
        centre = _array(section.motions[linear[0]].values)
        offset = ", ".join(f"{v:g}" for v in tool.offset_mm)
        figures.append(FigureSpec(
            "error_motions_tool", f"Positioning error at the tool point ({offset}) mm, {tool.frame} frame",
            "target position [mm]", f"[{MU}m]",
            [Series(x, y, f"{linear[0]} at the tool point", "line", COMPONENT_COLORS[0], y - 2 * s, y + 2 * s),
             Series(x, centre, f"{linear[0]} at the camera centre", "line", UNRESOLVED_COLOR),
             Series(x, y - centre, "Abbe term (angles \u00d7 offset)", "line", COMPONENT_COLORS[2])],
            "relative to the first stop; band \u00b12\u03c3; the Abbe term is what the angular error motions add "
            "at the tool point"))
    return figures


def has_error_motions(results: Results) -> bool:
    """Whether the results have error motions to show (SPEC 14: where the poses allow)."""
    return bool(error_motion_figures(results))


def error_motions_content(results: Results, figures: list[FigureSpec]) -> SectionContent:
    """The "Error motions" tab: its ``figures`` (:func:`error_motion_figures`), the table of motions."""
    rows = error_motion_rows(results)
    unresolved = [r[0] for r in rows if r[-1] != "resolved"]
    lines = [f"Not resolved (grey): {', '.join(unresolved)}." if unresolved else "Every error motion is resolved."]
    tool = results.error_motions.tool_point
    if tool:
        lines.append(f"Tool point {list(tool.offset_mm)} mm ({tool.frame} frame): the angular error motions add up "
                     f"to {tool.max_abs_abbe_um:.3g} \u00b5m (max |Abbe term|) to the positioning error there.")
    return SectionContent("Error motions", figures, lines, MOTION_HEADER, rows,
                          [None if r[-1] == "resolved" else UNRESOLVED_ROW for r in rows])


def error_motion_rows(results: Results | Mapping[str, Any]) -> list[list[str]]:
    """One row per motion: name, what, p-v over the targets, its noise p-v, median sigma, resolved."""
    section = as_results(results).error_motions
    rows = []
    for iso, m in (section.motions if section else {}).items():
        unit = f"{MU}m" if m.unit == "um" else f"{MU}rad"
        resolved = section.is_resolved(iso)
        rows.append([iso, what(iso), _fmt(m.span()), _fmt(m.noise_span()), _fmt(m.median_centred_sigma), unit,
                     "resolved" if resolved else "not resolved"])
    return rows


def _fmt(v: Any) -> str:
    x = num_or_nan(v)
    return "\u2014" if not np.isfinite(x) else f"{x:.3g}"


def paint_error_motions_page(flow: Any, results: Results | Mapping[str, Any], figure_height_mm: float) -> bool:
    """A new page with the error motions, when the results have them; False (nothing painted) otherwise."""
    results = as_results(results)
    figures = error_motion_figures(results)
    if not figures:
        return False
    section = results.error_motions
    flow.new_page()
    axes = " and ".join(section.axis_names)
    flow.heading(f"Error motions of the {axes} ax{'es' if ' and ' in axes else 'is'} (ISO 230-1)", 12)
    flow.paragraph(f"From {section.basis or ''}. Each motion is resolved when its profile over the targets "
                   "differs from zero beyond what noise alone gives (chi-square, p < 0.001) and its p-v exceeds "
                   "the noise p-v; positions.csv carries eax/ebx/ecx only where resolved.", size_pt=7.5,
                   color="#555555")
    flow.table(MOTION_HEADER, error_motion_rows(results),
               [14, 40, 20, 22, 22, 14, 28], size_pt=7.5, row_mm=4.0, align_right_from=2, align_left=(5, 6),
               colors=[None if r[-1] == "resolved" else UNRESOLVED_ROW for r in error_motion_rows(results)])
    from lps_gui.report.pages.reconcile import reconciliation_lines

    for spec in figures:
        flow.figure(spec, figure_height_mm)
    for line in reconciliation_lines(results):  # one reported figure per quantity; the other a cross-check
        flow.paragraph(line, size_pt=7.5, color="#555555")
    tool = section.tool_point
    if tool:
        flow.paragraph(f"Tool point {list(tool.offset_mm)} mm from the camera centre ({tool.frame} frame): "
                       f"the angular error motions add up to {_fmt(tool.max_abs_abbe_um)} {MU}m (max |Abbe "
                       "term|) to the positioning error there.", size_pt=8.0)
    return True
