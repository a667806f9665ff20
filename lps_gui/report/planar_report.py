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

from typing import Any

from lps_gui.report.planar_figures import planar_figures_from_results
from lps_gui.report.summary import Row, fmt, table_cells

PLANAR_TABLE_COLUMNS = (  # key, header, decimals, width mm
    ("index", "#", None, 8), ("run", "run", None, 7), ("direction", "dir", None, 7),
    ("target_x_mm", "X target\n[mm]", 3, 15), ("target_y_mm", "Y target\n[mm]", 3, 15),
    ("deviation_x_um", "dev X\n[\u00b5m]", 2, 14), ("deviation_y_um", "dev Y\n[\u00b5m]", 2, 14),
    ("sigma_x_um", "1\u03c3 X\n[\u00b5m]", 2, 13), ("sigma_y_um", "1\u03c3 Y\n[\u00b5m]", 2, 13),
    ("rms_px", "RMS\n[px]", 3, 11), ("truth_deviation_x_um", "truth X\n[\u00b5m]", 2, 14),
    ("truth_deviation_y_um", "truth Y\n[\u00b5m]", 2, 14), ("outlier", "outlier", None, 11),
)


def planar_summary_rows(results: dict[str, Any]) -> list[Row]:
    """Measured figures of a planar session, each with 1 sigma; U (k=2) is 2 sigma (noise only)."""
    pl = results["figures"]["planar"]
    rows = [
        Row("Squareness (angle +X to +Y minus 90\u00b0)", pl["squareness_urad"], "\u00b5rad",
            f"\u00b1{fmt(pl['squareness_sigma_urad'])} (1\u03c3), U(k=2) {fmt(2 * pl['squareness_sigma_urad'])}"),
        Row("Squareness", pl["squareness_um_per_m"], "\u00b5m/m"),
        Row("Scale error X", pl["scale_x_ppm"], "ppm",
            f"\u00b1{fmt(pl['scale_x_sigma_ppm'])} (1\u03c3), U(k=2) {fmt(2 * pl['scale_x_sigma_ppm'])}"),
        Row("Scale error Y", pl["scale_y_ppm"], "ppm",
            f"\u00b1{fmt(pl['scale_y_sigma_ppm'])} (1\u03c3), U(k=2) {fmt(2 * pl['scale_y_sigma_ppm'])}"),
    ]
    for axis, other in (("X", "Y"), ("Y", "X")):
        a = (pl.get("per_axis") or {}).get(axis)
        if not a:
            continue
        st = a.get("straightness") or {}
        rows.append(Row(f"Straightness of {axis} (in the plane, along {other}), worst line", a["straightness_um_max"],
                        "\u00b5m", f"{a['lines']} line(s); per-point 1\u03c3 {fmt(a['straightness_sigma_um'])} \u00b5m",
                        unresolved=_unresolved(st)))
        oop = a.get("out_of_plane")
        if oop:
            rows.append(Row(f"Straightness of {axis} out of the plane (along the normal), worst line", oop.get("span_um"),
                            "\u00b5m", f"per-target 1\u03c3 {fmt(oop.get('sigma_um'))} \u00b5m", unresolved=_unresolved(oop)))
        iso = (a.get("iso230_2") or {}).get("iso230_2") or {}
        for key, name in (("A_um", "accuracy A"), ("R_um", "repeatability R"), ("E_um", "systematic E"),
                          ("B_um", "reversal B")):
            if iso.get(key) is not None:
                rows.append(Row(f"{axis} ISO 230-2 {name} (worst line)", iso[key], "\u00b5m"))
    p = results["parameters"]
    rows.append(Row("Corner noise (a posteriori)", p["sigma_px"], "px"))
    rows.append(Row("Views used / outliers", float(p["n_used"]), "", f"{p['n_outliers']} outlier view(s)"))
    return rows


def _unresolved(span: dict[str, Any]) -> str:
    """"not resolved (noise p-v X)" for a p-v that noise alone could give (core.resolution), else empty."""
    from lps_gui.core.resolution import not_resolved_text

    if not span or span.get("resolved", True):
        return ""
    return not_resolved_text(span.get("noise_span_um"), "\u00b5m")


def planar_truth_rows(results: dict[str, Any]) -> list[Row]:
    tc = results.get("truth_comparison") or {}
    if tc.get("per_coordinate_rms_error_um") is None:
        return []
    ex, ey = tc["per_coordinate_rms_error_um"]
    return [
        Row(f"Position error RMS x ({tc['reference']})", ex, "\u00b5m"),
        Row(f"Position error RMS y ({tc['reference']})", ey, "\u00b5m"),
        Row("Mean reported 1\u03c3 per coordinate", tc["mean_sigma_um"], "\u00b5m"),
        Row("Mean (error/\u03c3)\u00b2", tc["z_mean_square"], ""),
        Row("True squareness (least-squares lines of the true path)", tc["squareness_urad"], "\u00b5rad"),
        Row("Squareness error", tc["squareness_error_urad"], "\u00b5rad", f"{fmt(tc['squareness_z'])} \u03c3"),
        Row("Scale X error", tc["scale_x_error_ppm"], "ppm"),
        Row("Scale Y error", tc["scale_y_error_ppm"], "ppm"),
    ] + ([Row("Out-of-plane displacement error RMS (board plane)", tc["out_of_plane_rms_error_um"], "\u00b5m",
              f"mean (error/\u03c3)\u00b2 {fmt(tc.get('out_of_plane_z_mean_square'))}")]
         if tc.get("out_of_plane_rms_error_um") is not None else [])


def planar_position_table(results: dict[str, Any]) -> tuple[list[str], list[list[str]], list[float]]:
    positions = sorted(results.get("positions") or [], key=lambda r: r.get("index", 0))
    has_truth = any(r.get("truth_deviation_x_um") is not None for r in positions)
    columns = [c for c in PLANAR_TABLE_COLUMNS if has_truth or not c[0].startswith("truth_")]
    body = table_cells(positions, columns)
    return [c[1] for c in columns], body, [float(c[3]) for c in columns]


def paint_planar_report(flow: Any, meta: dict[str, Any], results: dict[str, Any], title_rows: list[tuple[str, str]],
                        figure_height_mm: float) -> None:
    """Every page of a planar session's report onto ``flow`` (a :class:`report.layout.PdfFlow`)."""
    flow.heading("XY positioning stage \u2014 planar measurement report", 15)
    flow.space(1)
    flow.table(None, [[k, v] for k, v in title_rows], [32, 148], size_pt=8.5, row_mm=4.6, align_right_from=9)
    flow.heading("Axis geometry and per-axis figures (measured)", 11)
    rows = planar_summary_rows(results)
    flow.table(["figure", "value", "unit", "uncertainty / note"], [[r.name, r.text(), r.unit, r.note] for r in rows],
               [78, 30, 12, 60], align_right_from=1, align_left=(3,),
               colors=["#888888" if r.unresolved else None for r in rows])
    flow.paragraph("Uncertainties are from corner noise alone (1\u03c3 and U with k = 2); a board square-size error is a "
                   "common scale error of both axes and does not change squareness.", size_pt=7.5, color="#555555")
    for note in (results["figures"]["planar"].get("notes") or []):
        flow.paragraph(note, size_pt=7.5, color="#555555")
    truth = planar_truth_rows(results)
    if truth:
        flow.heading("Simulation only: against the simulator's truth", 11)
        flow.table(["figure", "value", "unit", "note"], [[r.name, r.text(), r.unit, r.note] for r in truth],
                   [78, 20, 14, 68], align_right_from=1, align_left=(3,), colors=["#555555"] * len(truth))
    flow.new_page()
    flow.heading("Plots")
    for spec in planar_figures_from_results(results):
        flow.figure(spec, figure_height_mm if spec.key != "error_map" else 1.6 * figure_height_mm)
    flow.new_page()
    flow.heading("Per-position results (1\u03c3: noise only)")
    header, body, widths = planar_position_table(results)
    colors = ["#c00000" if r[-1] else None for r in body]
    flow.table(header, body, widths, size_pt=6.3, row_mm=3.35, align_right_from=0, colors=colors)
