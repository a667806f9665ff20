"""Whole-process `lps estimate` of the paper's X axis against a row of targets (SPEC 13), from the shell.

The session is `lps simulate --points --preset paper-row` (121 stops over 1524 mm, six 10x7 targets of
30 mm at 340 mm pitch, 800 mm away, 0.1 px). `lps estimate` runs as a child process (interpreter start,
imports, reading the SPEC 13 corners.vnl, the row model's solve and sigmas, results.json, positions.csv,
summary.csv: everything the user waits for) beside cv2.calibrateCamera in this process on the same
corners (the targets' true points in the world frame, intrinsics from the session as a guess); the
ratio is the figure to watch. Goal: `lps estimate` under 2 s on the 2-core development machine.

    .venv/bin/python benchmarks/bench_targets_estimate.py [--dir /tmp/lps-bench-targets] [--repeats 3]

Timings are wall clock on a shared machine; the load average is printed with them.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_cli import LPS, load, run_child  # noqa: E402  (run from benchmarks/: its folder is on sys.path)


def row_session(root: Path) -> Path:
    folder = root / "paper-row"
    if not (folder / "corners.vnl").exists():
        subprocess.run(LPS + ["simulate", "--points", "--preset", "paper-row", str(folder)], check=True,
                       stdout=subprocess.DEVNULL)
    return folder


def calibrate_camera_s(folder: Path) -> tuple[float, int]:
    """Wall seconds of cv2.calibrateCamera on the session's corners (USE_INTRINSIC_GUESS), and the corners."""
    import cv2

    from lps_gui.core.geometry.rotation import exp_so3
    from lps_gui.io.corners.target_vnl import read_target_corners
    from lps_gui.io.session import Session

    session = Session.open(folder)
    targets = session.targets()
    table = read_target_corners(session.corners_path, targets)
    truth = {t["id"]: t for t in session.truth["targets"]}
    world = np.concatenate([t.board.object_points() @ exp_so3(np.asarray(truth[t.id]["rvec_rad"])).T
                            + np.asarray(truth[t.id]["p_mm"]) for t in targets]).astype(np.float32)
    objs, imgs = [], []
    for view in table.corners_px:
        seen = np.isfinite(view).all(axis=1)
        if seen.sum() >= 6:
            objs.append(world[seen])
            imgs.append(view[seen].astype(np.float32))
    intr = session.intrinsics()
    t0 = time.perf_counter()
    cv2.calibrateCamera(objs, imgs, intr.image_size, intr.camera_matrix.copy(), intr.dist.copy(),
                        flags=cv2.CALIB_USE_INTRINSIC_GUESS)
    return time.perf_counter() - t0, int(sum(len(o) for o in objs))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", type=Path, default=None, help="where the session is simulated (reused when present)")
    ap.add_argument("--repeats", type=int, default=3, help="runs of lps estimate; the best is printed")
    args = ap.parse_args()
    # an installed package has its bytecode cached; a shell with PYTHONDONTWRITEBYTECODE compiles every module
    # of every run (0.6 s here), which no user waits for
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    root = args.dir or Path(tempfile.mkdtemp(prefix="lps-bench-targets-"))
    root.mkdir(parents=True, exist_ok=True)
    folder = row_session(root)
    walls = []
    for _ in range(max(1, args.repeats)):
        with tempfile.TemporaryDirectory(dir=root) as out:
            walls.append(run_child(LPS + ["estimate", str(folder), "--out", out]))
    wall, peak, cpu = min(walls)
    calib, n = calibrate_camera_s(folder)
    print(f"paper row, 121 stops, 6 targets, {n} corners: lps estimate (whole process, best of {len(walls)}) {wall:.2f} s "
          f"(cpu {cpu:.2f} s, peak {peak:.0f} MB), cv2.calibrateCamera {calib:.2f} s, ratio {wall / calib:.2f}; "
          f"goal < 2 s ({load()})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
