"""`lps demo`: the simulated rig end to end (intrinsics, capture, detect, estimate, report)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from lps_gui.cli.option_types import nonnegative_finite, nonnegative_int, positive_finite

HELP = "run the whole simulated rig end to end and write report.pdf and the CSVs"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--quick", action="store_true", help="small camera and fewer stops (seconds, not minutes)")
    parser.add_argument("--out", type=Path, default=Path("demo-output"),
                        help="output folder (default demo-output): an existing or new folder; a name with a suffix is refused")
    parser.add_argument("--seed", type=nonnegative_int, default=0, help="random seed of the simulation")
    parser.add_argument("--planar", action="store_true", help="the planar pipeline on a simulated XY gantry (docs/planar.md)")
    parser.add_argument("--lightfield", action="store_true", help="the light field (docs/lightfield.md): measure, "
                        "compensate, capture a scene, rectify, HCI layout, epipolar check")
    parser.add_argument("--test", choices=("min-step", "settling"), help="an ASME B5.64 test on the simulated stage "
                        "(docs/asme-b5.64.md): min-step on a 3 um dead band, settling of a ringing stage; seconds")
    parser.add_argument("--lens-misfit", type=nonnegative_finite, default=0.0, metavar="PX",
                        help="a true lens with rational and thin-prism terms that the 5-coefficient model misses by PX "
                             "RMS over the image (real lenses: 0.03-0.3 px); default 0")
    parser.add_argument("--realism", choices=("off", "on", "strong"), default="off",
                        help="the simulator's realism (docs/validation.md): a true lens with rational and thin-prism "
                             "terms (on ~0.04 px, strong ~0.2 px beyond the 5-coefficient fit), prints off scale and "
                             "bowed, blur and noise varying over the image; default off")
    row = parser.add_mutually_exclusive_group()
    row.add_argument("--travel", type=positive_finite, metavar="MM",
                     help="the whole travel against a row of targets (docs/targets.md): the paper's X axis is 1524")
    row.add_argument("--preset", choices=("paper-row", "small-row"),
                     help="a row of targets from a simulation preset (paper-row: the paper's X axis)")


def run(args: argparse.Namespace) -> int:
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.errors import InputError
    from lps_gui.pipeline.demos.run import run_demo

    if (args.out.suffix or args.out.exists() or args.out.is_symlink()) and not args.out.is_dir():
        raise InputError(f"--out {args.out}: lps demo writes a folder of files; give a folder name without a suffix")

    t0 = time.monotonic()
    if args.planar and (args.travel or args.preset):
        raise InputError("--planar with --travel/--preset: a row of targets is one axis; drop --planar")
    if args.lens_misfit and args.realism != "off":
        raise InputError("--lens-misfit with --realism: each brings its own true lens; give one of them")
    if args.lightfield:
        if args.planar or args.travel or args.preset or args.test:
            raise InputError("--lightfield: runs on its own simulated rig; drop --planar/--travel/--preset/--test")
        return _lightfield(args, t0)
    if args.test:
        if args.planar or args.travel or args.preset:
            raise InputError("--test: the ASME B5.64 tests are single-axis tests of one board; drop --planar/--travel/--preset")
        if args.lens_misfit:
            raise InputError("--test with --lens-misfit: the ASME B5.64 demo keeps its own lens; drop --lens-misfit")
        if args.realism != "off":
            raise InputError("--test with --realism: the ASME demos simulate corners, not images; drop --realism")
        from lps_gui.pipeline.demos.asme import run_asme_demo

        res = run_asme_demo(args.out, args.test, seed=args.seed, say=lambda line: print(line, flush=True))
    else:
        res = run_demo(args.out, quick=args.quick, bar=ProgressBar, say=lambda line: print(line, flush=True), seed=args.seed,
                       planar=args.planar, travel_mm=args.travel, preset=args.preset,
                       lens_misfit_px=args.lens_misfit, realism=args.realism)
    print()
    if res.report_pdf is None:
        print(f"demo stopped before the report; files so far in {res.out_dir}")
        return 1
    print(f"report:  {res.report_pdf}")
    for path in res.reports:
        print(f"report:  {path}")
    for path in res.csvs:
        print(f"csv:     {path}")
    print(f"session: {res.session_dir}")
    print()
    for line in res.summary:
        print(f"  {line}")
    skipped = [s for s in res.steps if s.status != "done"]
    if skipped:
        print("\nnot the full chain: " + "; ".join(f"{s.name}: {s.message}" for s in skipped))
    print(f"\ndemo finished in {time.monotonic() - t0:.1f} s")
    return 0


def _lightfield(args: argparse.Namespace, t0: float) -> int:
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.pipeline.demos.lightfield import report_paths, run_lightfield_demo

    res = run_lightfield_demo(args.out, quick=args.quick, bar=ProgressBar, say=lambda line: print(line, flush=True),
                              seed=args.seed)
    print()
    for path in report_paths(res):
        print(f"report:  {path}")
    print(f"measurement: {res.measurement}")
    print()
    for line in res.summary:
        print(f"  {line}")
    print(f"\ndemo finished in {time.monotonic() - t0:.1f} s")
    return 0 if res.compensated is not None and res.compensated.hci is not None and res.hci_views_equal else 1
