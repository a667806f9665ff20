"""Estimation speed and memory on the paper's rig (issue 3 targets).

Prints, measured in this process: joint-LM time, hybrid time, cv2.calibrateCamera
time on the same corners and their ratios; peak memory of the joint solve; and
the joint time for K = 100, 400, 1600, 5000 views to show linear growth.
Targets: joint K=400 within 0.3 s on a 2-core machine, at least 3x faster
than cv2.calibrateCamera, time linear in K, memory O(K N).

Run: .venv/bin/python benchmarks/bench_estimate.py [--skip-calibrate]
"""
from __future__ import annotations

import argparse
import time
import tracemalloc
from dataclasses import replace

from lps_gui.blas_threads import limit_blas_threads

limit_blas_threads()  # as lps does, before numpy loads

import numpy as np  # noqa: E402

from lps_gui.allocator import tune_allocator  # noqa: E402
from lps_gui.core.estimator.estimate import EstimateOptions, estimate  # noqa: E402
from lps_gui.core.truth.simulate import observations_of, paper_rig_spec, simulate_views  # noqa: E402
from lps_gui.core.truth.stage_errors import StageErrorModel  # noqa: E402

ERRORS = StageErrorModel(scale_ppm=25.0, periodic_um=4.0, pitch_mm=5.0, backlash_um=6.0, repeatability_um=1.0)


def paper_case(K: int, seed: int = 0):
    spec = paper_rig_spec(seed=seed, noise_px=0.1, errors=ERRORS)
    spec = replace(spec, plan=replace(spec.plan, stop_mm=399.0, step_mm=399.0 / (K - 1)))
    views = simulate_views(spec)
    return spec, views, observations_of(spec, views)


def best_time(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def rms_error_um(est, views) -> float:
    return float(1e3 * np.sqrt(np.mean((est.state.s - np.asarray(views.truth["positions_mm"])) ** 2)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-calibrate", action="store_true", help="skip cv2.calibrateCamera (slow)")
    args = ap.parse_args()
    tune_allocator()

    spec, views, obs = paper_case(400)
    K, N = obs.K, obs.N
    print(f"paper rig: K={K} views, N={N} corners, noise 0.1 px, {spec.rig.intrinsics.image_size[0]}x{spec.rig.intrinsics.image_size[1]}")
    solve_only = EstimateOptions(method="joint", six_dof=False, detect_outliers=False)
    t_joint, est = best_time(lambda: estimate(obs, solve_only), 5)
    t_full, est_full = best_time(lambda: estimate(obs, EstimateOptions(method="joint")), 3)
    print(f"joint LM (init + LM + sigmas)        : {t_joint:7.3f} s   RMS error vs truth {rms_error_um(est, views):.2f} um  (target <= 0.3 s)")
    print(f"joint, full (+ outliers, 6-DOF)      : {t_full:7.3f} s   timings {({k: round(v, 3) for k, v in est_full.timings_s.items()})}")
    t_hybrid, est_h = best_time(lambda: estimate(obs, EstimateOptions(method="hybrid", six_dof=False, detect_outliers=False)), 1)
    print(f"hybrid (paper)                       : {t_hybrid:7.3f} s   RMS error vs truth {rms_error_um(est_h, views):.2f} um  ratio hybrid/joint {t_hybrid / t_joint:.1f}x")

    if not args.skip_calibrate:
        import cv2

        X = spec.rig.board.object_points().astype(np.float32)
        objs = [X] * K
        imgs = [c.astype(np.float32) for c in obs.corners_px]
        intr = spec.rig.intrinsics
        t0 = time.perf_counter()
        cv2.calibrateCamera(objs, imgs, intr.image_size, intr.camera_matrix.copy(), intr.dist.copy(), flags=cv2.CALIB_USE_INTRINSIC_GUESS)
        t_cal = time.perf_counter() - t0
        print(f"cv2.calibrateCamera (same corners)   : {t_cal:7.3f} s   ratio calibrate/joint {t_cal / t_joint:.1f}x  (target >= 3x)")

    tracemalloc.start()
    estimate(obs, solve_only)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    print(f"peak memory, joint solve             : {peak / 1e6:7.1f} MB = {peak / (K * N):.0f} bytes per corner")

    print("growth with K (same travel, finer steps):")
    base = None
    for k in (100, 400, 1600, 5000):
        _, v, o = paper_case(k, seed=1)
        t, e = best_time(lambda: estimate(o, solve_only), 2 if k <= 1600 else 1)
        tracemalloc.start()
        estimate(o, solve_only)
        _, pk = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        per_view_ms = 1e3 * t / k
        base = base or per_view_ms
        print(f"  K={k:5d}: {t:7.3f} s  {per_view_ms:6.3f} ms/view (x{per_view_ms / base:4.2f} of K=100)  peak {pk / 1e6:7.1f} MB ({pk / (k * N):.0f} B/corner)  RMS err {rms_error_um(e, v):.2f} um")


if __name__ == "__main__":
    main()
