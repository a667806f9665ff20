"""`lps compensate`: the compensation table of an estimated session, for a controller.

Examples::

    lps compensate run1 --format linuxcnc --out x.comp          # [JOINT_0] COMP_FILE = x.comp, COMP_FILE_TYPE = 0
    lps compensate run1 --format linuxcnc-offsets --out x.comp  # COMP_FILE_TYPE = 1
    lps compensate run1 --format csv --out comp.csv             # with sigmas; lps capture --compensation reads it
"""
from __future__ import annotations

import argparse

HELP = "compensation table of an estimated session (LinuxCNC, Mach4, CSV) and backlash settings"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from lps_gui.io.compensation_file import FORMATS

    p.add_argument("session", help="session folder with results.json (run lps estimate first)")
    p.add_argument("--format", required=True, choices=FORMATS, help="table format")
    p.add_argument("--out", required=True, metavar="FILE", help="table file to write")
    p.add_argument("--axis", default="X", choices=("X", "Y", "Z"),
                   help="controller axis of the backlash lines (default X); of a planar session, the axis whose table "
                        "is written (the skew settings come with either)")
    p.add_argument("--error-motions", metavar="FILE",
                   help="also write the six error motions (EXX ... ECX, SPEC 14) per nominal position as CSV")


def run(args: argparse.Namespace) -> int:
    from lps_gui.cli.out_path import check_out_file
    from lps_gui.pipeline.compensate import compensate_session

    check_out_file(args.out)
    if args.error_motions:
        check_out_file(args.error_motions, option="--error-motions", inputs=(args.out,))
    table, lines = compensate_session(args.session, args.format, args.out, args.axis, args.error_motions)
    worst = max(float(abs(table.offset_um(1)).max()), float(abs(table.offset_um(-1)).max()))
    kind = "bidirectional" if table.bidirectional else "one direction measured, its column repeated"
    print(f"{args.out}: {len(table.nominal_mm)} points {table.nominal_mm[0]:g}..{table.nominal_mm[-1]:g} mm ({kind}), "
          f"largest offset {worst:.2f} µm")
    if lines:
        b = table.backlash_um()
        print("controller settings" + (f" (backlash {b:.2f} µm)" if b is not None else "") + ":")
        for line in lines:
            print(f"  {line}")
    if args.error_motions:
        print(f"{args.error_motions}: the error motions per nominal position (empty where not resolved)")
    return 0
