"""`lps estimate`: positions of every stop with error bars, into results.json and CSVs."""
from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from lps_gui.cli.option_types import float_range, positive_finite
from lps_gui.io.results.keys import SIGMA_TOTAL_UM

if TYPE_CHECKING:  # the command's help stays instant: no numpy before run()
    from lps_gui.io.results.model import Results
    from lps_gui.io.results.sections import SpanResolution

HELP = "estimate the stage's true positions from a session's corners (joint LM by default)"


EXIT_DOUBTFUL = 4


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.epilog = ("exit status: 0 estimated, 4 results written but not trustworthy (the solver did not converge or the "
                "corner noise is implausible; the reason is printed), 2 bad input or the results could not be written")
    from lps_gui.core.estimator.methods import DEFAULT, METHODS  # no numpy: --help stays instant

    p.add_argument("session", help="session folder (session.json, captures.jsonl, corners.vnl)")
    p.add_argument("--method", default=DEFAULT, choices=METHODS,
                   help="joint LM (default), the paper's hybrid, per-view PnP, or full calibration (reference)")
    p.add_argument("--intrinsics", help="intrinsics JSON/YAML instead of the session's")
    p.add_argument("--out", help="where to write (default the session folder): an existing folder gets results.json "
                   "(and the CSVs) inside; a name ending in .json is the results file (CSVs beside it as "
                   "NAME-positions.csv, NAME-summary.csv); a name without suffix is a new folder")
    p.add_argument("--robust", action="store_true", help="Huber loss on corner residuals (joint)")
    p.add_argument("--outlier-k", type=float_range(1.0, 1e6), default=5.0,
                   help="robust sigmas that flag an outlier view (default 5; at least 1: below, most good views are flagged)")
    p.add_argument("--no-outliers", action="store_true", help="do not look for outlier views")
    p.add_argument("--self-calibrate", action=argparse.BooleanOptionalAction, default=None,
                   help="intrinsics free with their covariance as prior (joint); default: on for a session with "
                        "targets (a row), off otherwise")
    p.add_argument("--no-six-dof", action="store_true", help="skip straightness and angular errors")
    p.add_argument("--grid-window-mm", type=positive_finite, help="hybrid: grid half-width (default 0.5 mm)")
    p.add_argument("--grid-resolution-mm", type=positive_finite, help="hybrid: final grid spacing (default 0.0001 mm)")
    p.add_argument("--threshold-px", type=positive_finite, help="hybrid: stop when the RMS reprojection error is below T px")


def run(args: argparse.Namespace) -> int:
    import sys
    from pathlib import Path

    from lps_gui.cli.out_path import resolve_out
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.io.results.model import as_results
    from lps_gui.io.session_lock import SessionLock
    from lps_gui.pipeline.estimate import estimate_session
    from lps_gui.pipeline.session_checks import result_doubts

    options = {
        "robust": args.robust,
        "outlier_k": args.outlier_k,
        "detect_outliers": not args.no_outliers,
        "self_calibrate": args.self_calibrate,
        "six_dof": not args.no_six_dof,
        "grid_window_mm": args.grid_window_mm,
        "grid_resolution_mm": args.grid_resolution_mm,
        "threshold_px": args.threshold_px,
    }
    out = resolve_out(args.out, "results.json", args.session, (".json",), "lps estimate", own_session=args.session,
                      inputs=[p for p in (args.intrinsics,) if p]) if args.out else None
    if out is not None:  # its CSVs go beside it: each checked like the results file
        from lps_gui.cli.out_path import check_out_file
        from lps_gui.io.results.document import result_set_paths

        for path in result_set_paths(out):
            check_out_file(path, allow=(path.name,), own_session=args.session)
    lock = SessionLock(args.session) if out is None and Path(args.session).is_dir() else None
    if lock is not None:
        lock.__enter__()  # refused at once when a capture or detection holds the session
    try:
        document = estimate_session(args.session, args.method, options, args.intrinsics, out, progress=ProgressBar("estimate"))
    finally:
        if lock is not None:
            lock.__exit__(None, None, None)
    results = as_results(document, str(out or Path(args.session) / "results.json"))  # read once for the lines below
    print(format_summary(results))
    from lps_gui.io.results.history import stale_report_message

    if (stale := stale_report_message(args.session)) and not args.out:
        print(stale, file=sys.stderr)
    doubts = result_doubts(results.parameters)
    for doubt in doubts:
        print(f"lps estimate: warning: {doubt}", file=sys.stderr)
    return EXIT_DOUBTFUL if doubts else 0


def _g(value: object, spec: str) -> str:
    """``value`` formatted with ``spec``, or "n/a" when it is missing (null in results.json)."""
    return format(value, spec) if isinstance(value, (int, float)) else "n/a"


def _fit_line(results: Results, kind: str) -> str:
    """"method joint: 30/30 views used, 0 outlier(s), corner noise 0.200 px, 0.05 s" (``kind``: " (planar X,Y)")."""
    p = results.parameters
    return (f"method {results.method}{kind}: {p.n_used}/{p.n_views} views used, {p.n_outliers} outlier(s), "
            f"corner noise {_g(p.sigma_px, '.3f')} px, {_g(results.timings_s.get('total', 0.0), '.2f')} s")


def _median(values: list[float]) -> float:
    return sorted(values)[len(values) // 2]


def format_planar_summary(results: Results) -> str:
    """The first lines of a planar session: squareness, per-axis scale, straightness, truth."""
    from lps_gui.core.metrology.resolution import not_resolved_text
    from lps_gui.report.pages.summary import truth_check_lines, view_flags

    pl = results.figures.planar
    lines = [_fit_line(results, " (planar X,Y)")]
    if pl is not None:
        lines.append(f"squareness {_g(pl.squareness_urad, '+.1f')} +- {_g(pl.squareness_sigma_urad, '.1f')} µrad "
                     f"({_g(pl.squareness_um_per_m, '+.1f')} µm/m), scale X {_g(pl.scale_x_ppm, '+.1f')} +- "
                     f"{_g(pl.scale_x_sigma_ppm, '.1f')} ppm, Y {_g(pl.scale_y_ppm, '+.1f')} +- "
                     f"{_g(pl.scale_y_sigma_ppm, '.1f')} ppm (1 sigma)")
    used = [r for r in results.positions if r.used and r.number("sigma_x_um")]
    if used:
        sx, sy = (_median([r.number(k) for r in used]) for k in ("sigma_x_um", "sigma_y_um"))
        lines.append(f"position sigma median x {sx:.2f} µm, y {sy:.2f} µm (1 sigma, noise only)")

    def span_text(d: SpanResolution | None) -> str:
        if d is None or d.span_um is None:
            return "-"
        return f"{d.span_um:.2f} µm" if d.resolved else not_resolved_text(d.noise_span_um, "µm")

    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl.per_axis.get(axis) if pl else None
        if a:
            iso = a.iso230_2.iso230_2 if a.iso230_2 else None
            extra = "".join(f", {k[:-3]} {iso.number(k):.2f} µm" for k in ("A_um", "R_um", "E_um")
                            if iso and iso.number(k) is not None)
            straight = span_text(a.straightness) if a.straightness else f"{_g(a.straightness_um_max, '.2f')} µm"
            oop = f"; out of plane {span_text(a.out_of_plane)}" if a.out_of_plane else ""
            lines.append(f"{axis}: {a.lines} line(s), straightness along {other} {straight}{oop}{extra}")
    lines += [f"outlier view {f.index}: {f.message}" if f.index is not None else f"warning: {f.message}"
              for f in view_flags(results)]
    tc = results.truth_comparison
    if tc and tc.per_coordinate_rms_error_um:
        ex, ey = tc.per_coordinate_rms_error_um
        lines.append(f"against truth ({tc.reference}): RMS error x {_g(ex, '.2f')} µm, y {_g(ey, '.2f')} µm, mean "
                     f"reported sigma {_g(tc.mean_sigma_um, '.2f')} µm; squareness error "
                     f"{_g(tc.squareness_error_urad, '+.1f')} µrad ({_g(tc.squareness_z, '+.1f')} sigma)")
    return "\n".join(lines + truth_check_lines(results))


def format_summary(results: Results) -> str:
    """A few lines a person reads first: what was measured and how well."""
    from lps_gui.report.pages.summary import truth_check_lines, view_flags

    if results.planar:
        return format_planar_summary(results)
    single, iso = results.figures.single_run, results.figures.iso230_2
    lines = [_fit_line(results, "")]
    if single:
        lines.append(
            f"mean step {_g(single.mean_step_mm, '.5f')} mm (std {_g(single.step_std_um, '.2f')} µm), "
            f"max |deviation| {_g(single.max_abs_deviation_um, '.2f')} µm, scale {_g(single.scale_ppm, '+.1f')} ppm"
        )
    sig = [v for r in results.positions if (v := r.number(SIGMA_TOTAL_UM)) is not None and r.used]
    if sig:
        lines.append(f"position sigma (total) median {_g(_median(sig), '.2f')} µm")
    if iso and (iso.number("A_um") is not None or iso.number("E_um") is not None):
        parts = [f"{k[:-3]} {_g(iso.number(k), '.2f')} µm" for k in ("A_um", "R_um", "E_um", "B_um", "M_um")
                 if iso.number(k) is not None]
        lines.append("ISO 230-2: " + ", ".join(parts))
    if results.asme_b5_64 is not None and results.asme_b5_64.has_test:  # an ASME B5.64 test session (docs/asme-b5.64.md)
        from lps_gui.report.pages.asme import test_lines

        lines += [f"ASME B5.64: {line}" for line in test_lines(results)]
    lines += [f"outlier view {f.index}: {f.message}" if f.index is not None else f"warning: {f.message}"
              for f in view_flags(results)]
    tc = results.truth_comparison
    if tc and tc.position_rms_error_um is not None:
        lines.append(
            f"against truth: position RMS error {_g(tc.position_rms_error_um, '.2f')} µm "
            f"(max {_g(tc.position_max_abs_error_um, '.2f')} µm), mean reported sigma {_g(tc.mean_sigma_um, '.2f')} µm"
        )
    if tc and tc.board_plane_rms_error_um is not None:
        lines.append(
            f"against truth at the board plane (what a constant-orientation model sees; Abbe term RMS {_g(tc.abbe_rms_um, '.2f')} µm): "
            f"RMS error {_g(tc.board_plane_rms_error_um, '.2f')} µm, mean (error/sigma)^2 {_g(tc.board_plane_z_mean_square, '.2f')}"
        )
    return "\n".join(lines + truth_check_lines(results))
