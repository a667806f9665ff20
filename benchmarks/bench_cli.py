"""Whole-process speed as the user waits for it: `lps estimate` and `lps detect` run from the shell.

Each command runs as a child process (interpreter start, imports, reading
corners.vnl, the solve, writing results: everything the user waits for) and
is printed beside a reference measured in the same run on the same data:

- `lps estimate` at K views (point sessions from `lps simulate --points`,
  paper rig, 540 corners a view) against cv2.calibrateCamera alone on the same
  corners (in this process, started from the session's intrinsics, as the
  `calibrate` method does): ratio = lps wall time / calibrateCamera wall time.
- `lps detect --force` on a rendered 1920x1080 paper-rig session against plain
  cv2.findChessboardCornersSB on every image (same number of worker processes),
  with the decode-only rate beside them.

Peak memory is the child's maximum resident set size from the OS (wait4).

    .venv/bin/python benchmarks/bench_cli.py [--sizes 100,400,1600,5000] [--images 120] [--workers 2]
                                             [--dir /tmp/lps-bench-cli] [--no-detect] [--no-estimate]

Sessions are simulated once and reused. Timings are wall-clock on a shared
machine; the load average is printed with them.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

LPS = [sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main())"]

# How `lps simulate --points --preset paper-rig` reaches K views: 400 stops 1 mm apart per run by default.
PLAN_ARGS = {100: ["--stops", "100"], 400: [], 1600: ["--runs", "4"], 5000: ["--stops", "500", "--runs", "10"]}


def plan_args(k: int) -> list[str]:
    if k in PLAN_ARGS:
        return PLAN_ARGS[k]
    if k <= 400:
        return ["--stops", str(k)]
    if k % 400 == 0:
        return ["--runs", str(k // 400)]
    raise SystemExit(f"--sizes: {k} views is neither <= 400 nor a multiple of 400")


# A small launcher forks and execs the command and reports the child's rusage: a child forked straight
# from this (large) process would count this process's pages in its peak RSS.
LAUNCHER = """
import os, sys
pid = os.fork()
if pid == 0:
    os.execv(sys.argv[2], sys.argv[2:])
_, status, ru = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(f"{os.waitstatus_to_exitcode(status)} {ru.ru_maxrss} {ru.ru_utime + ru.ru_stime}")
"""


def run_child(cmd: list[str]) -> tuple[float, float, float]:
    """Wall time (s), peak RSS (MB) and CPU time (s, user + system, its worker processes included) of a child."""
    with tempfile.NamedTemporaryFile("r", suffix=".rusage") as report:
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-S", "-c", LAUNCHER, report.name, *cmd],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        wall = time.perf_counter() - t0
        code, maxrss_kb, cpu = report.read().split()
    if proc.returncode != 0 or int(code) not in (0, 3):
        raise SystemExit(f"{' '.join(cmd[3:])} failed ({code}): {proc.stderr.decode(errors='replace').strip().splitlines()[-1:]}")
    return wall, int(maxrss_kb) / 1024.0, float(cpu)


def load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def point_session(root: Path, k: int) -> Path:
    folder = root / f"points-{k}"
    if not (folder / "corners.vnl").exists():
        shutil.rmtree(folder, ignore_errors=True)
        subprocess.run(LPS + ["simulate", "--points", "--preset", "paper-rig", *plan_args(k), str(folder)],
                       check=True, stdout=subprocess.DEVNULL)
    return folder


def calibrate_camera_s(folder: Path) -> tuple[float, float]:
    """Wall and CPU seconds of cv2.calibrateCamera on the session's corners, from its intrinsics (USE_INTRINSIC_GUESS)."""
    import cv2

    from lps_gui.io.board_file import read_board
    from lps_gui.io.corners.vnl import read_corners_vnl
    from lps_gui.io.intrinsics_file import read_intrinsics

    board = read_board(folder / "board.json")
    intr = read_intrinsics(folder / "intrinsics.json")
    corners = read_corners_vnl(folder / "corners.vnl", board.n_corners).corners_px
    X = board.object_points().astype(np.float32)
    objs, imgs = [], []
    for view in corners:
        seen = np.isfinite(view).all(axis=1)
        if seen.sum() >= 6:
            objs.append(X[seen])
            imgs.append(view[seen].astype(np.float32))
    t0, c0 = time.perf_counter(), time.process_time()
    cv2.calibrateCamera(objs, imgs, intr.image_size, intr.camera_matrix.copy(), intr.dist.copy(),
                        flags=cv2.CALIB_USE_INTRINSIC_GUESS)
    return time.perf_counter() - t0, time.process_time() - c0


def bench_estimate(root: Path, sizes: list[int]) -> None:
    print("lps estimate, whole process (paper rig, 540 corners/view) vs cv2.calibrateCamera alone on the same corners")
    print("  (ratio = lps / calibrateCamera, wall clock; the CPU ratio beside it is the one a busy machine distorts less)")
    print(f"{'K':>6} {'corners':>9} {'lps s':>8} {'peak MB':>8} {'calib s':>8} {'ratio':>6} {'lps cpu':>8} {'cal cpu':>8} {'ratio':>6}"
          f"  {'s/1000 views':>12}")
    for k in sizes:
        folder = point_session(root, k)
        with tempfile.TemporaryDirectory(dir=root) as out:
            wall, peak, cpu = run_child(LPS + ["estimate", str(folder), "--out", out])
        calib, calib_cpu = calibrate_camera_s(folder)
        print(f"{k:>6} {k * 540:>9} {wall:>8.2f} {peak:>8.0f} {calib:>8.2f} {wall / calib:>6.2f} {cpu:>8.2f} {calib_cpu:>8.2f}"
              f" {cpu / calib_cpu:>6.2f}  {1000 * wall / k:>12.2f}   ({load()})", flush=True)


def _decode(paths: list[str]) -> int:
    import cv2

    cv2.setNumThreads(1)
    for p in paths:
        if cv2.imdecode(np.fromfile(p, np.uint8), cv2.IMREAD_GRAYSCALE) is None:
            raise RuntimeError(f"cannot decode {p}")
    return len(paths)


def _plain_sb(args: tuple[list[str], int, int]) -> int:
    import cv2

    paths, cols, rows = args
    cv2.setNumThreads(1)
    found = 0
    for p in paths:
        img = cv2.imdecode(np.fromfile(p, np.uint8), cv2.IMREAD_GRAYSCALE)
        found += bool(cv2.findChessboardCornersSB(img, (cols, rows))[0])
    return found


def _pool_rate(fn, tasks, workers: int, n: int) -> float:
    """Images/s of ``fn`` over ``tasks`` in a fresh pool (its start-up included, like the CLI's)."""
    from lps_gui.pipeline.detect import process_context

    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=workers, mp_context=process_context()) as pool:
        list(pool.map(fn, tasks))
    return n / (time.perf_counter() - t0)


def bench_detect(root: Path, n_images: int, workers: int) -> None:
    from lps_gui.io.session import Session

    folder = root / f"rendered-{n_images}"
    if not (folder / "session.json").exists() or len(list((folder / "images").glob("*.png"))) < n_images:
        shutil.rmtree(folder, ignore_errors=True)
        t0 = time.perf_counter()
        subprocess.run(LPS + ["simulate", "--preset", "paper-rig", "--stops", str(n_images), str(folder)],
                       check=True, stdout=subprocess.DEVNULL)
        print(f"rendered {n_images} images in {time.perf_counter() - t0:.0f} s -> {folder}")
    session = Session.open(folder)
    paths = [str(folder / r.file) for r in session.records()]
    board = session.board()
    chunks = [paths[i::workers] for i in range(workers)]
    _pool_rate(_decode, chunks, workers, len(paths))  # warm the page cache
    decode = _pool_rate(_decode, chunks, workers, len(paths))
    wall, peak, cpu = run_child(LPS + ["detect", str(folder), "--force", "--workers", str(workers)])
    rate = len(paths) / wall
    sb = _pool_rate(_plain_sb, [(c, board.cols, board.rows) for c in chunks], workers, len(paths))
    print(f"lps detect, whole process: {len(paths)} PNG 1920x1080, board {board.cols}x{board.rows}, {workers} workers ({load()})")
    print(f"  decode only            : {decode:6.1f} images/s")
    print(f"  lps detect --force     : {rate:6.1f} images/s  ({wall:.2f} s, peak {peak:.0f} MB; {rate / decode:.2f} of decode;"
          f" {cpu:.2f} s CPU with its workers = {len(paths) * workers / cpu:.0f} images/s on {workers} idle cores)")
    print(f"  plain findChessboardSB : {sb:6.1f} images/s  (lps detect / SB = {rate / sb:.1f}x)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="100,400,1600,5000", help="views K of the estimate runs")
    ap.add_argument("--images", type=int, default=120, help="rendered images of the detect run")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--dir", default="/tmp/lps-bench-cli")
    ap.add_argument("--no-estimate", action="store_true")
    ap.add_argument("--no-detect", action="store_true")
    args = ap.parse_args()
    root = Path(args.dir)
    root.mkdir(parents=True, exist_ok=True)
    print(f"{os.cpu_count()} cores, {load()}")
    if not args.no_estimate:
        bench_estimate(root, [int(k) for k in args.sizes.split(",") if k])
    if not args.no_detect:
        bench_detect(root, args.images, args.workers)
    return 0


if __name__ == "__main__":
    sys.exit(main())
