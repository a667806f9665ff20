"""`lps capture --live / --report`: live results beside the capture (:mod:`lps_gui.pipeline.live`).

Flags are printed the moment they are found (the frame and what to check),
so the operator can stop (Ctrl-C: everything listed is kept), fix and
``--resume``; a complete capture ends in results.json and, with
``--report``, the PDF.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from lps_gui.cli.option_types import int_range


def add_live_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("live results (docs/capture.md)")
    g.add_argument("--live", action="store_true", help="detect every frame as it is written (corners.vnl), estimate "
                   "every few stops and flag a board out of view, an exposure or sharpness jump, an outlier, a moving camera")
    g.add_argument("--report", nargs="?", const="", default=None, metavar="PDF",
                   help="implies --live: when the last frame is written, estimate and write the report "
                        "(default SESSION/report.pdf)")
    g.add_argument("--live-every", type=int_range(1, 100000), default=None, metavar="N",
                   help="views between running estimates (default 2)")


def report_path(args: argparse.Namespace, folder: Path | str) -> Path | None:
    """Where --report writes (checked before anything is captured: a bad name must not cost a capture)."""
    if args.report is None:
        return None
    from lps_gui.cli.out_path import resolve_out

    return resolve_out(args.report or None, "report.pdf", folder, (".pdf",), "lps capture --report", own_session=folder)


def wants_live(args: argparse.Namespace) -> bool:
    return bool(args.live) or args.report is not None


def start_live(args: argparse.Namespace, engine: Any) -> Any:
    """The :class:`LiveCapture` of ``engine``, started, printing its flags to stderr; None without --live/--report."""
    if not wants_live(args):
        return None
    from lps_gui.errors import InputError
    from lps_gui.pipeline.live import ESTIMATE_EVERY, LiveCapture

    every = ESTIMATE_EVERY if args.live_every is None else args.live_every
    why = LiveCapture.unsupported(engine.session)
    if why:
        raise InputError(f"--live: {why}")
    live = LiveCapture(engine, estimate_every=every)

    def show(event: Any) -> None:
        if event.kind in ("flag", "error"):
            print(f"\nlps capture: {event.message}", file=sys.stderr, flush=True)

    live.subscribe(show)
    live.start()
    return live


def finish_live(args: argparse.Namespace, live: Any, summary: Any) -> None:
    """Wait for the live work; on a complete capture print where results.json and the report are."""
    if live is None:
        return
    report = report_path(args, summary.folder) or False
    results = live.finish(summary, report=report)
    if results is not None:
        print(f"results: {Path(summary.folder) / 'results.json'} ({len(live.flags)} live flag(s))")
        if report:
            print(f"report: {report}")
