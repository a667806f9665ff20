"""`lps lightfield`: a scene session rectified into a light field with measured positions (SPEC 17).

Examples::

    lps capture --scene run2 --compensation comp.csv --out scene2
    lps lightfield scene2 --out scene2-lf          # views/, lightfield.json, hci/, colmap/, nerfstudio/, EPIs
    lps lightfield scene2 --measurement run2b --out lf   # positions from another measurement of the same stage
"""
from __future__ import annotations

import argparse

HELP = "rectify a scene session's views to one virtual camera: lightfield.json, HCI layout, COLMAP, nerfstudio"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="scene session folder (lps capture --scene MEASURED --out SCENE)")
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the light field")
    p.add_argument("--measurement", metavar="SESSION",
                   help="measured session to take positions from (default: the one the scene session names)")
    p.add_argument("--epi-row", type=int, metavar="ROW", help="image row of the epipolar-plane images (default: middle)")


def run(args: argparse.Namespace) -> int:
    import sys

    from lps_gui.cli.out_path import check_out_folder
    from lps_gui.cli.progress_bar import ProgressBar
    from lps_gui.pipeline.lightfield import check_lines, make_lightfield

    check_out_folder(args.out)
    res = make_lightfield(args.scene, args.out, args.measurement, args.epi_row, progress=ProgressBar("lightfield"))
    g = res.grid
    print(f"{args.out}: {res.n_views} rectified views, grid {' x '.join(map(str, g.shape))}, "
          f"spacing {', '.join(f'{v:.5f}' for v in g.spacing_mm)} mm, worst {float(g.z.max()):.1f} sigma off uniform")
    print(f"  HCI layout: {res.hci.parent}" if res.hci else f"lps lightfield: {res.refusal}",
          file=sys.stdout if res.hci else sys.stderr)
    for line in check_lines(res.check):
        print(f"  {line}")
    return 0
