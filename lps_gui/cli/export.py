"""`lps export`: every capture's measured camera pose for 3-D and light-field tools.

Examples::

    lps export run1 --format colmap --out run1-colmap         # cameras.txt, images.txt, points3D.txt
    lps export run1 --format nerfstudio --out run1-ns         # transforms.json
    lps export run1 --format csv --out run1-poses             # camera_centres.csv: nominal and measured
"""
from __future__ import annotations

import argparse

HELP = "export the measured camera poses (COLMAP text model, nerfstudio transforms.json, CSV)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("session", help="session folder with results.json (run lps estimate first)")
    p.add_argument("--format", required=True, choices=("colmap", "nerfstudio", "csv"))
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the exported files")
    p.add_argument("--straightness", default="auto", choices=("auto", "on", "off"),
                   help="add the measured straightness to the line (auto: when resolved)")


def run(args: argparse.Namespace) -> int:
    from lps_gui.cli.out_path import check_out_folder
    from lps_gui.pipeline.export import export_session

    check_out_folder(args.out)
    res = export_session(args.session, args.format, args.out, args.straightness)
    print(f"{args.out}: {res.n_exported} poses ({'line + straightness' if res.straightness_used else 'on the fitted line'}); "
          f"{len(res.excluded)} views left out (excluded.txt)")
    return 0
