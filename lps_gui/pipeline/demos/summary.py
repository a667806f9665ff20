"""What `lps demo` prints at the end: five lines a newcomer reads first, for a line or a gantry.

Every figure is read from results.json; the truth beside it is results.json's
``truth_comparison`` (one reduction, :func:`lps_gui.sim.truth.reduce_truth`),
never recomputed here.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.metrology.iso230_spectrum import UNDEFINED_TEXT
from lps_gui.core.truth.simulate import SimulationSpec
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import PlanarAxis, PlanarFigures, SingleRun, TruthComparison

PAPER_SPEC = {"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0}  # the paper's stage table


def truth_errors(results: Results | dict[str, Any]) -> dict[str, float] | None:
    """results.json's ``truth_comparison`` in the demo's words: position error RMS and max, median sigma (um)."""
    tc = as_results(results).truth_comparison
    if tc is None or tc.position_rms_error_um is None:
        return None
    return {"rms_um": tc.position_rms_error_um, "max_um": _or_nan(tc.position_max_abs_error_um),
            "median_sigma_um": _or_nan(tc.median_sigma_um)}


def _or_nan(x: float | None) -> float:
    return np.nan if x is None else x


def summary_lines(results: Results | dict[str, Any], spec: SimulationSpec) -> list[str]:
    """Five lines a newcomer reads first: what was measured, the stage figures, the verdict, the truth check."""
    from lps_gui.report.pages.summary import extremes_rows, fmt, truth_check_lines
    from lps_gui.report.pages.verdict import verdicts

    results = as_results(results)
    p = results.parameters
    single = results.figures.single_run or SingleRun()
    n_out = sum(r.outlier for r in results.positions)
    plan = spec.plan
    ext = {r.name: r.text() if r.unresolved or r.value is None else f"{r.text()} {r.unit}" for r in extremes_rows(results)}
    verdict = ", ".join(f"{v.name} {v.verdict}" for v in verdicts(results, PAPER_SPEC))
    U = results.uncertainty.expanded_k2_um if results.uncertainty else None
    te = truth_errors(results)
    tc = results.truth_comparison
    truth_line = ("error against truth: " + (f"position RMS {te['rms_um']:.2f} \u00b5m, max {te['max_um']:.2f} \u00b5m "
                                             f"(median 1-sigma {te['median_sigma_um']:.2f} \u00b5m)" if te else "no truth"))
    if te and tc and tc.board_plane_rms_error_um is not None:
        truth_line += (f"; at the board plane RMS {tc.board_plane_rms_error_um:.2f} \u00b5m "
                       f"(camera-centre error includes the Abbe term distance x pitch/yaw, RMS {_or_nan(tc.abbe_rms_um):.2f} \u00b5m)")
    return [
        f"views: {'?' if p.n_views is None else p.n_views} ({len(plan.targets())} targets x {len(plan.run_directions())} "
        f"directions x {plan.runs} runs), {n_out} flagged outlier(s); RMS residual {fmt(p.rms_px)} px",
        f"positioning: scale {fmt(single.scale_ppm)} ppm, periodic " + (
            UNDEFINED_TEXT if single.periodic_amplitude_um is None else
            f"{fmt(single.periodic_amplitude_um)} \u00b5m at {fmt(single.periodic_period_mm)} mm")
        + f", mean step {fmt(single.mean_step_mm, 6)} mm",
        f"straightness p-v (board plane) v1 {ext.get('Max straightness v1 (peak-to-valley)', '-')}, "
        f"v2 {ext.get('Max straightness v2 (peak-to-valley)', '-')}; image rotation p-v "
        f"{ext.get('Image rotation (peak-to-valley)', '-')}; max |roll| {ext.get('Max |roll|', '-')}, "
        f"|pitch| {ext.get('Max |pitch|', '-')}, |yaw| {ext.get('Max |yaw|', '-')}",
        f"paper's spec (\u00b120 \u00b5m, \u00b15 \u00b5m, 38 \u00b5m): {verdict}"
        + (f"; U (k = 2) {fmt(U, 2)} \u00b5m over the travel" if U is not None else ""),
        truth_line,
    ] + truth_check_lines(results)


def _v(x: Any, digits: int = 1) -> str:
    return "n/a" if x is None else f"{float(x):+.{digits}f}"


def _s(x: Any, digits: int = 1) -> str:
    return "n/a" if x is None else f"{float(x):.{digits}f}"


def planar_summary_lines(results: Results | dict[str, Any]) -> list[str]:
    """A gantry's lines: each figure with its sigma, beside the truth from ``truth_comparison``."""
    results = as_results(results)
    p = results.parameters
    pl = results.figures.planar or PlanarFigures()
    tc = results.truth_comparison or TruthComparison()
    lines = [
        f"views: {'?' if p.n_views is None else p.n_views} ({'?' if p.n_used is None else p.n_used} used, "
        f"{p.n_outliers or 0} flagged outlier(s)); RMS residual {_s(p.rms_px, 3)} px",
        f"squareness {_v(pl.squareness_urad)} \u00b1 {_s(pl.squareness_sigma_urad)} \u00b5rad "
        f"({_v(pl.squareness_um_per_m)} \u00b5m/m); truth {_v(tc.squareness_urad)} \u00b5rad"
        + (f" (the stage model's {_v(tc.number('model_squareness_urad'))}; the truth is the angle of the true path's "
           "least-squares lines, tilted by the axes' straightness)"
           if tc.number("model_squareness_urad") is not None else ""),
    ]
    for axis in ("x", "y"):
        lines.append(f"scale {axis.upper()} {_v(pl.number(f'scale_{axis}_ppm'))} \u00b1 "
                     f"{_s(pl.number(f'scale_{axis}_sigma_ppm'))} ppm; truth {_v(tc.number(f'scale_{axis}_ppm'))} ppm")
    from lps_gui.core.metrology.resolution import not_resolved_text

    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl.per_axis.get(axis) or PlanarAxis()
        st = a.straightness
        value = (f"{_s(a.straightness_um_max, 2)} \u00b5m" if st is None or st.resolved is None or st.resolved
                 else not_resolved_text(st.noise_span_um, "\u00b5m"))  # noise alone could give it: no finding
        lines.append(f"straightness of {axis} (along {other}, worst line) {value} "
                     f"(per-point 1-sigma {_s(a.straightness_sigma_um, 2)} \u00b5m); "
                     f"truth {_s(tc.number(f'straightness_{axis.lower()}_um'), 2)} \u00b5m")
    if tc.position_rms_error_um is not None:
        per = tc.per_coordinate_rms_error_um or (None, None)
        lines.append(f"error against truth ({tc.reference or ''}): position RMS {_s(tc.position_rms_error_um, 2)}"
                     f" \u00b5m (x {_s(per[0], 2)}, y {_s(per[1], 2)}), max {_s(tc.position_max_abs_error_um, 2)}"
                     f" \u00b5m; RMS 1-sigma {_s(tc.mean_sigma_um, 2)} \u00b5m; "
                     f"mean (error/sigma)^2 {_s(tc.z_mean_square, 2)}")
    else:
        lines.append("error against truth: no truth")
    from lps_gui.report.pages.summary import truth_check_lines

    return lines + truth_check_lines(results)
