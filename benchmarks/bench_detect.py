"""Detection speed and accuracy on a rendered paper-rig session (1920x1080, 18x30 board).

Prints, from one run on the same PNG files with the same number of worker
processes: images/s of the full pipeline (`detect_session`: decode, track,
refine, verify, write corners.vnl), of plain cv2.findChessboardCornersSB on
every image, and of decoding alone, with their ratios; and the corner RMS
error against the renderer's truth for the pipeline and for SB + cornerSubPix.

    .venv/bin/python benchmarks/bench_detect.py [--images 400] [--workers 2] [--dir /tmp/lps-bench-detect]

The session is rendered once (about a minute) and reused by later runs.
Timings are wall-clock on a shared machine: expect noise of 10-20 %.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from lps_gui.camera.detection import orient, refine, subpix_half_window
from lps_gui.camera.processes import process_context
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec, true_views
from lps_gui.io.session import SESSION_FILE, Session
from lps_gui.pipeline.detect import detect_session
from lps_gui.sim.images import simulate_image_session


def _decode(paths: list[str]) -> int:
    cv2.setNumThreads(1)
    for p in paths:
        img = cv2.imdecode(np.fromfile(p, np.uint8), cv2.IMREAD_GRAYSCALE)
        assert img is not None
    return len(paths)


def _plain_sb(args: tuple[list[str], int, int]) -> list[np.ndarray | None]:
    """findChessboardCornersSB at full size on every image (and cornerSubPix for the accuracy figure)."""
    paths, cols, rows = args
    cv2.setNumThreads(1)
    board = Board(cols, rows, 1.0)
    out = []
    for p in paths:
        img = cv2.imdecode(np.fromfile(p, np.uint8), cv2.IMREAD_GRAYSCALE)
        ok, c = cv2.findChessboardCornersSB(img, (cols, rows))
        out.append(orient(c.reshape(-1, 2).astype(float), board) if ok else None)
    return out


def _parallel(fn, tasks, workers):
    with ProcessPoolExecutor(max_workers=workers, mp_context=process_context()) as pool:
        return list(pool.map(fn, tasks))


def _rms(found: np.ndarray, truth: np.ndarray) -> float:
    return float(np.sqrt(np.nanmean(np.sum((found - truth) ** 2, axis=-1))))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--images", type=int, default=400)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--sb-images", type=int, default=60, help="images timed with plain SB (it is slow)")
    ap.add_argument("--noise", type=float, default=2.0, help="image noise sigma, grey levels")
    ap.add_argument("--dir", default="/tmp/lps-bench-detect")
    args = ap.parse_args()

    plan = Plan(start_mm=0.0, stop_mm=float(args.images - 1), step_mm=1.0)
    spec = paper_rig_spec(plan=plan)
    folder = Path(args.dir) / f"paper-{args.images}-noise{args.noise:g}"
    if not (folder / SESSION_FILE).exists() or len(Session.open(folder).records()) < args.images:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)
        t0 = time.perf_counter()
        simulate_image_session(spec, folder, noise_grey=args.noise, workers=args.workers)
        print(f"rendered {args.images} images in {time.perf_counter() - t0:.1f} s -> {folder}")
    session = Session.open(folder)
    records = session.records()
    paths = [str(folder / r.file) for r in records]
    board = spec.rig.board
    _, R, t, _ = true_views(spec, np.random.default_rng(spec.seed))
    truth = project_board(R, t, board.object_points(), spec.rig.intrinsics)  # shape (K, N, 2)
    W = args.workers
    size_mb = sum(os.path.getsize(p) for p in paths) / 1e6

    chunks = [paths[i :: W] for i in range(W)]
    _parallel(_decode, chunks, W)  # warm the page cache and the pool start-up path
    t0 = time.perf_counter()
    _parallel(_decode, chunks, W)
    decode_rate = len(paths) / (time.perf_counter() - t0)

    t0 = time.perf_counter()
    table = detect_session(folder, workers=W, force=True)
    pipeline_rate = len(paths) / (time.perf_counter() - t0)
    pipe_rms = _rms(table.corners_px, truth)

    n_sb = min(args.sb_images, len(paths))
    sb_paths = paths[:n_sb]
    sb_chunks = [(sb_paths[i :: W], board.cols, board.rows) for i in range(W)]
    t0 = time.perf_counter()
    sb_parts = _parallel(_plain_sb, sb_chunks, W)
    sb_rate = n_sb / (time.perf_counter() - t0)
    sb_found: list[np.ndarray | None] = [None] * n_sb
    for i, part in enumerate(sb_parts):
        sb_found[i::W] = part
    sb_err, sbsp_err = [], []
    for k, c in enumerate(sb_found):
        if c is None:
            continue
        img = cv2.imread(sb_paths[k], cv2.IMREAD_GRAYSCALE)
        sb_err.append(c - truth[k])
        sbsp_err.append(refine(img, c, subpix_half_window(c, board)) - truth[k])
    sb_rms = _rms(np.array(sb_err), 0.0)
    sbsp_rms = _rms(np.array(sbsp_err), 0.0)
    pipe_rms_subset = _rms(table.corners_px[:n_sb], truth[:n_sb])

    print(f"session: {len(paths)} PNG images 1920x1080 ({size_mb / len(paths):.2f} MB each), board 30x18, "
          f"noise sigma {args.noise:g} grey levels, {W} worker processes, {len(table.failed)} failed")
    print(f"decode only          : {decode_rate:7.1f} images/s")
    print(f"full pipeline        : {pipeline_rate:7.1f} images/s   (ratio to decode {pipeline_rate / decode_rate:.2f}, target >= 0.5)")
    print(f"plain SB (full size) : {sb_rate:7.1f} images/s   (pipeline / SB = {pipeline_rate / sb_rate:.1f}x, target >= 5x; SB on {n_sb} images)")
    print(f"corner RMS vs truth  : pipeline {pipe_rms:.4f} px over all {len(paths)} images (target < 0.1)")
    print(f"                       on the {n_sb} SB images: pipeline {pipe_rms_subset:.4f} px, SB {sb_rms:.4f} px, "
          f"SB + cornerSubPix {sbsp_rms:.4f} px")
    _positions_vs_bound(session)
    return 0


def _positions_vs_bound(session: Session) -> None:
    """LPS positions from these corners (joint LM) against truth, in units of their sigma (the CRB at the fitted noise)."""
    try:
        from lps_gui.core.estimator.estimate import estimate
        from lps_gui.pipeline.estimate import make_options, observations_from_session

        obs = observations_from_session(session)
        est = estimate(obs, make_options("joint"))
    except Exception as exc:  # the estimator is another module's; report, do not fail the benchmark
        print(f"positions vs bound   : skipped ({type(exc).__name__}: {exc})")
        return
    axis = np.asarray(session.truth["axis_mm"])
    ref = est.reference_view
    ok = est.used.copy()
    ok[ref] = False
    err_um = 1e3 * (est.state.s - (axis - axis[ref]))[ok]
    sigma_um = 1e3 * est.sigma_s_mm[ok]
    rms_err = float(np.sqrt(np.mean(err_um**2)))
    print(f"positions vs bound   : RMS error {rms_err:.3f} um, mean sigma {np.mean(sigma_um):.3f} um, "
          f"ratio {rms_err / np.mean(sigma_um):.2f} (target <= 2), mean z^2 {np.mean((err_um / sigma_um) ** 2):.2f}")


if __name__ == "__main__":
    sys.exit(main())
