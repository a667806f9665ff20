"""`lps estimate`: positions of every stop with error bars, into results.json and CSVs."""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import positive_finite

HELP = "estimate the stage's true positions from a session's corners (joint LM by default)"


EXIT_DOUBTFUL = 4


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.epilog = ("exit status: 0 estimated, 4 results written but not trustworthy (the solver did not converge or the "
                "corner noise is implausible; the reason is printed), 2 bad input or the results could not be written")
    p.add_argument("session", help="session folder (session.json, captures.jsonl, corners.vnl)")
    p.add_argument("--method", default="joint", choices=("joint", "hybrid", "pnp", "calibrate"),
                   help="joint LM (default), the paper's hybrid, per-view PnP, or full calibration (reference)")
    p.add_argument("--intrinsics", help="intrinsics JSON/YAML instead of the session's")
    p.add_argument("--out", help="where to write (default the session folder): an existing folder gets results.json "
                   "(and the CSVs) inside; a name ending in .json is the results file (CSVs beside it as "
                   "NAME-positions.csv, NAME-summary.csv); a name without suffix is a new folder")
    p.add_argument("--robust", action="store_true", help="Huber loss on corner residuals (joint)")
    p.add_argument("--outlier-k", type=positive_finite, default=5.0, help="robust sigmas that flag an outlier view (default 5)")
    p.add_argument("--no-outliers", action="store_true", help="do not look for outlier views")
    p.add_argument("--self-calibrate", action="store_true", help="intrinsics free with their covariance as prior (joint)")
    p.add_argument("--no-six-dof", action="store_true", help="skip straightness and angular errors")
    p.add_argument("--grid-window-mm", type=positive_finite, help="hybrid: grid half-width (default 0.5 mm)")
    p.add_argument("--grid-resolution-mm", type=positive_finite, help="hybrid: final grid spacing (default 0.0001 mm)")
    p.add_argument("--threshold-px", type=positive_finite, help="hybrid: stop when the RMS reprojection error is below T px")


def run(args: argparse.Namespace) -> int:
    import sys
    from pathlib import Path

    from lps_gui.cli.out_path import resolve_out
    from lps_gui.cli.progress_bar import ProgressBar
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
    out = resolve_out(args.out, "results.json", args.session, (".json",), "lps estimate") if args.out else None
    lock = SessionLock(args.session) if out is None and Path(args.session).is_dir() else None
    if lock is not None:
        lock.__enter__()  # refused at once when a capture or detection holds the session
    try:
        results = estimate_session(args.session, args.method, options, args.intrinsics, out, progress=ProgressBar("estimate"))
    finally:
        if lock is not None:
            lock.__exit__(None, None, None)
    print(format_summary(results))
    from lps_gui.io.results_history import stale_report_message

    if (stale := stale_report_message(args.session)) and not args.out:
        print(stale, file=sys.stderr)
    doubts = result_doubts(results)
    for doubt in doubts:
        print(f"lps estimate: warning: {doubt}", file=sys.stderr)
    return EXIT_DOUBTFUL if doubts else 0


def _g(value: object, spec: str) -> str:
    """``value`` formatted with ``spec``, or "n/a" when it is missing (null in results.json)."""
    return format(value, spec) if isinstance(value, (int, float)) else "n/a"


def format_planar_summary(results: dict) -> str:
    """The first lines of a planar session: squareness, per-axis scale, straightness, truth."""
    p, pl = results["parameters"], results["figures"]["planar"]
    lines = [
        f"method {results['method']} (planar X,Y): {p['n_used']}/{p['n_views']} views used, {p['n_outliers']} outlier(s), "
        f"corner noise {p['sigma_px']:.3f} px, {results['timings_s'].get('total', 0.0):.2f} s",
        f"squareness {pl['squareness_urad']:+.1f} +- {pl['squareness_sigma_urad']:.1f} µrad "
        f"({pl['squareness_um_per_m']:+.1f} µm/m), scale X {pl['scale_x_ppm']:+.1f} +- {pl['scale_x_sigma_ppm']:.1f} ppm, "
        f"Y {pl['scale_y_ppm']:+.1f} +- {pl['scale_y_sigma_ppm']:.1f} ppm (1 sigma)",
    ]
    sig = [(r["sigma_x_um"], r["sigma_y_um"]) for r in results["positions"] if r["used"] and r["sigma_x_um"]]
    if sig:
        sx, sy = sorted(s[0] for s in sig), sorted(s[1] for s in sig)
        lines.append(f"position sigma median x {sx[len(sx) // 2]:.2f} µm, y {sy[len(sy) // 2]:.2f} µm (1 sigma, noise only)")
    from lps_gui.core.resolution import not_resolved_text

    def span_text(d: dict | None) -> str:
        if not d or d.get("span_um") is None:
            return "-"
        return f"{d['span_um']:.2f} µm" if d.get("resolved") else not_resolved_text(d.get("noise_span_um"), "µm")

    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl["per_axis"].get(axis)
        if a:
            iso = (a.get("iso230_2") or {}).get("iso230_2") or {}
            extra = "".join(f", {k[:-3]} {iso[k]:.2f} µm" for k in ("A_um", "R_um", "E_um") if iso.get(k) is not None)
            straight = span_text(a.get("straightness")) if a.get("straightness") else f"{a['straightness_um_max']:.2f} µm"
            oop = f"; out of plane {span_text(a['out_of_plane'])}" if a.get("out_of_plane") else ""
            lines.append(f"{axis}: {a['lines']} line(s), straightness along {other} {straight}{oop}{extra}")
    for f in results["flags"]:
        lines.append(f"outlier view {f['index']}: {f['message']}")
    tc = results.get("truth_comparison") or {}
    if tc.get("per_coordinate_rms_error_um"):
        ex, ey = tc["per_coordinate_rms_error_um"]
        lines.append(f"against truth ({tc['reference']}): RMS error x {ex:.2f} µm, y {ey:.2f} µm, mean reported sigma "
                     f"{tc['mean_sigma_um']:.2f} µm; squareness error {tc['squareness_error_urad']:+.1f} µrad "
                     f"({tc['squareness_z']:+.1f} sigma)")
    return "\n".join(lines)


def format_summary(results: dict) -> str:
    """A few lines a person reads first: what was measured and how well."""
    if len(results.get("axes") or ["X"]) == 2:
        return format_planar_summary(results)
    p, fig = results["parameters"], results["figures"]
    single = fig.get("single_run") or {}
    lines = [
        f"method {results['method']}: {p['n_used']}/{p['n_views']} views used, {p['n_outliers']} outlier(s), "
        f"corner noise {_g(p['sigma_px'], '.3f')} px, {_g(results['timings_s'].get('total', 0.0), '.2f')} s",
    ]
    if single:
        lines.append(
            f"mean step {_g(single.get('mean_step_mm'), '.5f')} mm (std {_g(single.get('step_std_um'), '.2f')} µm), "
            f"max |deviation| {_g(single.get('max_abs_deviation_um'), '.2f')} µm, scale {_g(single.get('scale_ppm'), '+.1f')} ppm"
        )
    sig = [r["sigma_total_um"] for r in results["positions"] if r.get("sigma_total_um") is not None and r["used"]]
    if sig:
        lines.append(f"position sigma (total) median {_g(sorted(sig)[len(sig) // 2], '.2f')} µm")
    iso = fig.get("iso230_2") or {}
    if iso.get("A_um") is not None or iso.get("E_um") is not None:
        parts = [f"{k[:-3]} {_g(iso[k], '.2f')} µm" for k in ("A_um", "R_um", "E_um", "B_um", "M_um") if iso.get(k) is not None]
        lines.append("ISO 230-2: " + ", ".join(parts))
    asme = results.get("asme_b5_64") or {}
    if asme.get("incremental_step") or asme.get("settling"):  # an ASME B5.64 test session (docs/asme-b5.64.md)
        from lps_gui.report.asme_pages import test_lines

        lines += [f"ASME B5.64: {line}" for line in test_lines(results)]
    for f in results["flags"]:
        lines.append(f"outlier view {f['index']}: {f['message']}")
    tc = results.get("truth_comparison")
    if tc and tc.get("position_rms_error_um") is not None:
        lines.append(
            f"against truth: position RMS error {_g(tc['position_rms_error_um'], '.2f')} µm "
            f"(max {_g(tc['position_max_abs_error_um'], '.2f')} µm), mean reported sigma {_g(tc['mean_sigma_um'], '.2f')} µm"
        )
    if tc and tc.get("board_plane_rms_error_um") is not None:
        lines.append(
            f"against truth at the board plane (what a constant-orientation model sees; Abbe term RMS {_g(tc['abbe_rms_um'], '.2f')} µm): "
            f"RMS error {_g(tc['board_plane_rms_error_um'], '.2f')} µm, mean (error/sigma)^2 {_g(tc['board_plane_z_mean_square'], '.2f')}"
        )
    return "\n".join(lines)
