"""`lps compare BEFORE AFTER`: the as-found / as-left PDF of two estimated sessions of one stage."""
from __future__ import annotations

import argparse
from pathlib import Path

HELP = "as-found / as-left report: deviation curves overlaid, ISO 230-2 figures side by side, improvement"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("before", type=Path, help="estimated session before compensation (as found)")
    p.add_argument("after", type=Path, help="estimated session after compensation (as left)")
    p.add_argument("--out", type=Path, default=None, help="PDF to write (default AFTER/as-found-as-left.pdf)")


def run(args: argparse.Namespace) -> int:
    from lps_gui.errors import InputError
    from lps_gui.pipeline.comparable import require_comparable
    from lps_gui.pipeline.compensate import session_results
    from lps_gui.report.pdf.compare import comparison_rows, write_comparison

    before, after = (session_results(folder, "compare") for folder in (args.before, args.after))
    axes = [",".join(r.axes) for r in (before, after)]
    if axes[0] != axes[1]:
        raise InputError(f"lps compare: {args.before} measured {axes[0]} and {args.after} {axes[1]} (one planar, one a "
                         "line); compare two sessions of the same stage and axes")
    if axes[0] != "X":
        raise InputError(f"lps compare: {args.before} and {args.after} are planar (X,Y) sessions; the as-found / as-left "
                         "report compares line sessions only")
    require_comparable(before, after, args.before, args.after)
    if args.out is not None:
        from lps_gui.cli.out_path import resolve_out

        args.out = resolve_out(args.out, "as-found-as-left.pdf", args.after, (".pdf",), "lps compare", own_session=args.after,
                               inputs=(args.before, args.after))
    path = write_comparison(args.before, args.after, args.out)
    for name, b, a, factor in comparison_rows(before, after):
        print(f"{name}: {b} -> {a} \u00b5m, improvement {factor}")
    print(f"report: {path}")
    return 0
