"""The PDF pages of a planar (XY) session (SPEC 10): geometry first, then the error map.

Page 1: what was measured, the axis geometry (squareness in urad and um/m,
per-axis scale, each with its 1-sigma and U (k=2)), per-axis ISO 230-2
figures and straightness from the plan's lines, and, for a simulated
session, the truth on a separate block labelled as such. Then the 2-D error
map and the per-axis plots, and the per-position table. Text rows are
plain data (:func:`planar_summary_rows`, :func:`planar_position_table`)
so tests read exactly what is printed; Qt only where painting.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import TruthComparison
from lps_gui.io.results.verdict_rows import (  # noqa: F401  (names the pages and tests use)
    SQUARENESS_CHECK,
    axis_results,
    planar_figure_us,
    planar_figures_k2,
    planar_verdicts,
)
from lps_gui.report.figures.plots import planar_figures_from_results
from lps_gui.report.pages import sections as R
from lps_gui.report.pages.error_motions import paint_error_motions_page
from lps_gui.report.pages.summary import DASH, Row, fmt, table_cells
from lps_gui.report.pages.targets import targets_section
from lps_gui.report.pages.verdict import overall

PLANAR_TABLE_COLUMNS = (  # key, header, decimals, width mm
    ("index", "#", None, 8), ("run", "run", None, 7), ("direction", "dir", None, 7),
    ("target_x_mm", "X target\n[mm]", 3, 15), ("target_y_mm", "Y target\n[mm]", 3, 15),
    ("deviation_x_um", "dev X\n[\u00b5m]", 2, 14), ("deviation_y_um", "dev Y\n[\u00b5m]", 2, 14),
    ("sigma_x_um", "1\u03c3 X\n[\u00b5m]", 2, 13), ("sigma_y_um", "1\u03c3 Y\n[\u00b5m]", 2, 13),
    ("rms_px", "RMS\n[px]", 3, 11), ("truth_deviation_x_um", "truth X\n[\u00b5m]", 2, 14),
    ("truth_deviation_y_um", "truth Y\n[\u00b5m]", 2, 14), ("outlier", "outlier", None, 11),
)


def _trust_note(tc: TruthComparison | None, error_key: str, z_key: str | None, u: float | None, unit: str) -> str:
    """A figure the simulator's truth shows off by more than its U: "not trusted" with the numbers, else empty."""
    err = tc.number(error_key) if tc else None
    if err is None or u is None or abs(err) <= u:
        return ""
    z = tc.number(z_key) if z_key else None
    return (f"not trusted: the truth is {fmt(abs(err))} {unit} off" + (f" ({fmt(abs(z), 2)} \u03c3)" if z is not None else "")
            + ", beyond U; a source is missing from the budget")


def planar_summary_rows(results: Results | dict[str, Any]) -> list[Row]:
    """Measured figures of a planar session with 1 sigma and U (k = 2).

    U is read from results.json ``uncertainty.figures_k2`` (the one source the
    line report uses) and is 2 sigma of corner noise where the results carry
    no budget. A simulated session whose truth is off by more than U says so.
    """
    results = as_results(results)
    pl = results.figures.planar
    if pl is None:
        raise InputError(f"{results.source}: a planar session without 'figures.planar'; re-run `lps estimate`")
    us = planar_figure_us(results)  # U and "not resolved" of each figure: the ones summary.csv states
    tc = results.truth_comparison
    u_sq, u_x, u_y = (us[k][0] for k in ("squareness_urad", "scale_x_ppm", "scale_y_ppm"))

    def note(sigma: float | None, unit: str, trust: str) -> str:
        return "; ".join(t for t in (f"1\u03c3 {fmt(sigma)} {unit}", trust) if t)

    rows = [
        Row("Squareness (angle +X to +Y minus 90\u00b0)", pl.squareness_urad, "\u00b5rad",
            note(pl.squareness_sigma_urad, "\u00b5rad", _trust_note(tc, "squareness_error_urad", "squareness_z", u_sq,
                                                                        "\u00b5rad")),
            key="squareness_urad", u_k2=u_sq),
        Row("Squareness", pl.squareness_um_per_m, "\u00b5m/m", "the same angle: 1 \u00b5rad = 1 \u00b5m/m",
            key="squareness_um_per_m", u_k2=u_sq),
        Row("Scale error X", pl.scale_x_ppm, "ppm",
            note(pl.scale_x_sigma_ppm, "ppm", _trust_note(tc, "scale_x_error_ppm", None, u_x, "ppm")),
            key="scale_x_ppm", u_k2=u_x),
        Row("Scale error Y", pl.scale_y_ppm, "ppm",
            note(pl.scale_y_sigma_ppm, "ppm", _trust_note(tc, "scale_y_error_ppm", None, u_y, "ppm")),
            key="scale_y_ppm", u_k2=u_y),
    ]
    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl.per_axis.get(axis)
        if not a:
            continue
        ax, ot = axis.lower(), other.lower()
        u, unresolved = us[f"straightness_{ax}_along_{ot}_max"]  # unresolved: no value, hence no U
        rows.append(Row(f"Straightness of {axis} (in the plane, along {other}), worst line", a.straightness_um_max,
                        "\u00b5m", f"{a.lines} line(s); per-point 1\u03c3 {fmt(a.straightness_sigma_um)} \u00b5m",
                        unresolved=unresolved, key=f"straightness_{ax}_along_{ot}_max",
                        u_k2=u))
        oop = a.out_of_plane
        if oop:
            rows.append(Row(f"Straightness of {axis} out of the plane (along the normal), worst line", oop.span_um,
                            "\u00b5m", f"per-target 1\u03c3 {fmt(oop.sigma_um)} \u00b5m",
                            unresolved=us[f"out_of_plane_straightness_{ax}_max"][1],
                            key=f"out_of_plane_straightness_{ax}_max"))
        iso = a.iso230_2.iso230_2 if a.iso230_2 else None
        for key, name in (("A_um", "accuracy A"), ("R_um", "repeatability R"), ("E_um", "systematic E"),
                          ("B_um", "reversal B")):
            if iso and iso.number(key) is not None:  # U from that axis's budget, the U its verdict row compares
                rows.append(Row(f"{axis} ISO 230-2 {name} (worst line)", iso.number(key), "\u00b5m",
                                key=f"iso230_2_{ax}_{key[:-3]}", u_k2=us[f"iso230_2_{ax}_{key[:-3]}"][0]))
    p = results.parameters
    n_used = p.n_used if p.n_used is not None else DASH
    rows.append(Row("Corner noise (a posteriori)", p.sigma_px, "px"))
    rows.append(Row("Views used / total", None if p.n_used is None else float(p.n_used), "",
                    f"{p.n_outliers} outlier view(s)", shown=f"{n_used} / {p.n_views if p.n_views is not None else n_used}"))
    return rows


def planar_truth_rows(results: Results | dict[str, Any]) -> list[Row]:
    tc = as_results(results).truth_comparison
    if tc is None or tc.per_coordinate_rms_error_um is None:
        return []
    ex, ey = tc.per_coordinate_rms_error_um
    return [
        Row(f"Position error RMS x ({tc.reference})", ex, "\u00b5m"),
        Row(f"Position error RMS y ({tc.reference})", ey, "\u00b5m"),
        Row("Mean reported 1\u03c3 per coordinate", tc.mean_sigma_um, "\u00b5m"),
        Row("Mean (error/\u03c3)\u00b2", tc.z_mean_square, ""),
        Row("True squareness (least-squares lines of the true path)", tc.squareness_urad, "\u00b5rad"),
        Row("Squareness error", tc.squareness_error_urad, "\u00b5rad", f"{fmt(tc.squareness_z)} \u03c3"),
        Row("Scale X error", tc.scale_x_error_ppm, "ppm"),
        Row("Scale Y error", tc.scale_y_error_ppm, "ppm"),
    ] + ([Row("Out-of-plane displacement error RMS (board plane)", tc.out_of_plane_rms_error_um, "\u00b5m",
              f"mean (error/\u03c3)\u00b2 {fmt(tc.out_of_plane_z_mean_square)}")]
         if tc.out_of_plane_rms_error_um is not None else [])


def planar_position_table(results: Results | dict[str, Any]) -> tuple[list[str], list[list[str]], list[float]]:
    positions = as_results(results).sorted_positions()
    has_truth = any(r.get("truth_deviation_x_um") is not None for r in positions)
    columns = [c for c in PLANAR_TABLE_COLUMNS if has_truth or not c[0].startswith("truth_")]
    body = table_cells(positions, columns)
    return [c[1] for c in columns], body, [float(c[3]) for c in columns]


def paint_planar_report(flow: Any, meta: dict[str, Any], results: Results, title_rows: list[tuple[str, str]],
                        figure_height_mm: float) -> None:
    """Every page of a planar session's report onto ``flow`` (a :class:`report.layout.PdfFlow`).

    The verdict, per-target, environment and budget sections are the line
    report's (:mod:`lps_gui.report.pages.sections`), painted per axis where the
    results hold them.
    """
    flow.heading("XY positioning stage \u2014 planar measurement report", 15)
    from lps_gui.report.pages.summary import truth_check_lines

    for line in truth_check_lines(results):  # a simulated session whose truth contradicts the report says so first
        flow.paragraph(line, size_pt=9.0, color="#c00000")
    spec = R.stage_spec(meta, results)
    axes = {axis: ar for axis in "XY" if (ar := axis_results(results, axis)) is not None}
    verdict_rows = planar_verdicts(results, spec) if spec else []  # the rows results.json and summary.csv state
    flow.heading("Verdict", 11)
    flow.paragraph(overall(verdict_rows) if spec else R.NO_SPEC, size_pt=10.0 if spec else 8.5,
                   color=R.overall_color(verdict_rows) if spec else R.GREY)
    if verdict_rows:
        R.verdict_table(flow, verdict_rows)
        flow.paragraph(R.DECISION_RULE, size_pt=R.NOTE_SIZE, color=R.GREY)
    elif spec:
        flow.paragraph("The specification is given, but neither axis has ISO 230-2 figures to compare (they need "
                       "both directions or two runs per line).", color=R.GREY)
    flow.heading("Axis geometry and per-axis figures (measured)", 11)
    R.figure_table(flow, planar_summary_rows(results))
    budget = bool(planar_figures_k2(results))
    flow.paragraph(("U (k = 2) of the scales from each axis's uncertainty budget (see below); squareness: 2σ "
                    "of corner noise. " if budget else
                    "U (k = 2) is 2\u03c3 of corner noise alone: these results carry no uncertainty budget. ")
                   + "A board square-size error is a common scale error of both axes and does not change squareness.",
                   size_pt=7.5, color=R.GREY)
    for note in results.figures.planar.notes if results.figures.planar else ():
        flow.paragraph(note, size_pt=7.5, color=R.GREY)
    truth = planar_truth_rows(results)
    if truth:
        flow.heading("Simulation only: against the simulator's truth", 11)
        flow.table(["figure", "value", "unit", "note"], [[r.name, r.text(), r.unit, r.note] for r in truth],
                   [78, 20, 14, 68], align_right_from=1, align_left=(3,), colors=[R.GREY] * len(truth))
    R.identification_blocks(flow, meta, results, title_rows)
    for axis, ar in axes.items():
        R.iso_section(flow, ar, f"ISO 230-2 per target, {axis} axis (worst line)")
    targets_section(flow, results)  # a constellation of targets (SPEC 13)
    if results.environment or results.uncertainty:
        flow.new_page()
        per_axis = results.uncertainty.per_axis if results.uncertainty else {}
        if not per_axis:
            R.uncertainty_sections(flow, results)
        for i, (axis, unc) in enumerate(per_axis.items()):
            R.uncertainty_sections(flow, replace(results, uncertainty=unc), axis=axis, environment=i == 0)
    flow.new_page()
    flow.heading("Plots")
    for spec_fig in planar_figures_from_results(results):
        flow.figure(spec_fig, figure_height_mm if spec_fig.key != "error_map" else 1.6 * figure_height_mm)
    paint_error_motions_page(flow, results, figure_height_mm)  # SPEC 14, when the results have them
    flow.new_page()
    flow.heading("Per-position results (1\u03c3: noise only)")
    header, body, widths = planar_position_table(results)
    colors = ["#c00000" if r[-1] else None for r in body]
    flow.table(header, body, widths, size_pt=6.3, row_mm=3.35, align_right_from=0, colors=colors)


def has_planar(results: Results) -> bool:
    """Two axes (SPEC 10): the planar report instead of the line report."""
    return results.planar


def planar_panel_rows(results: Results) -> list[tuple[str, str, str, str]] | None:
    """The results panel's figures table of a planar session (figure, value, U (k = 2), unit and note): page 1's
    rows and its truth check; None when the results carry no planar figures (the line's table then)."""
    if results.figures.planar is None:
        return None
    rows = planar_summary_rows(results)
    if results.truth_comparison and results.truth_comparison.position_rms_error_um is not None:
        rows += [replace(r, name=f"Truth: {r.name}") for r in planar_truth_rows(results)]
    return [(r.name, r.text(), r.u_text(), f"{r.unit}  {r.note}".strip()) for r in rows]


def planar_positions(results: Results) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the per-position table the report prints (for the results panel)."""
    return planar_position_table(results)[:2]
