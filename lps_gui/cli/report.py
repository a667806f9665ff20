"""`lps report SESSION`: the PDF report of an estimated session."""
from __future__ import annotations

import argparse
from pathlib import Path

HELP = "write the PDF report of an estimated session (reads SESSION/results.json)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("session", type=Path, help="session folder holding results.json (run `lps estimate` first)")
    parser.add_argument("--out", type=Path, default=None, help="PDF to write (default SESSION/report.pdf)")


def run(args: argparse.Namespace) -> int:
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.report.pdf import write_report

    path = write_report(args.session, out=args.out, progress=ProgressBar("report"))
    print(f"report: {path}")
    return 0
