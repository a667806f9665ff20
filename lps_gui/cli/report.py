"""`lps report SESSION`: the PDF report of an estimated session."""
from __future__ import annotations

import argparse
from pathlib import Path

from lps_gui.cli.out_path import out_help

HELP = "write the PDF report of an estimated session (reads SESSION/results.json)"

EXIT_STALE = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("exit status: 0 report written, 3 written but results.json is older than the session's files "
                     "(re-run `lps estimate`), 2 bad input or the report could not be written (the old one is kept)")
    parser.add_argument("session", type=Path, help="session folder holding results.json (run `lps estimate` first)")
    parser.add_argument("--out", type=Path, default=None, help=out_help("report.pdf", (".pdf",), "SESSION/report.pdf"))


def run(args: argparse.Namespace) -> int:
    import sys

    from lps_gui.cli.out_path import resolve_out
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.errors import InputError
    from lps_gui.pipeline.session_checks import stale_inputs
    from lps_gui.report.pdf.document import load_results, write_report

    folder = args.session
    if not folder.is_dir():
        raise InputError(f"{folder}: session folder not found; check the path")
    if not (folder / "results.json").exists() and not (folder / "session.json").exists():
        raise InputError(f"{folder}: not a session folder (no session.json or results.json); give the folder "
                         "`lps capture` or `lps simulate` made")
    if (folder / "session.json").exists() or (folder / "session.json").is_symlink():
        from lps_gui.io.image_file import check_regular_file

        # session.json as every command reads it: a regular file inside, no link, no FIFO (the report reads it later)
        check_regular_file(folder / "session.json", "session file", follow_symlinks=False)
    out = resolve_out(args.out, "report.pdf", folder, (".pdf",), "lps report", own_session=folder)
    from lps_gui.io.atomic import remove_orphan_temps

    remove_orphan_temps(out.parent)  # a report killed mid-write left its temp file (only dead writers' are removed)
    results = load_results(folder)
    path = write_report(folder, results=results, out=out, progress=ProgressBar("report"))
    print(f"report: {path}")
    changed = stale_inputs(folder, results)
    if changed:
        print(f"lps report: warning: results.json is stale: {', '.join(changed)} changed since `lps estimate`; "
              f"run `lps estimate {folder}` and report again", file=sys.stderr)
        return EXIT_STALE
    return 0
