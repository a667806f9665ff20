"""Speed of the target-row models (SPEC 13, 14) beside cv2.calibrateCamera on the same corners.

The paper's X axis: 121 stops over 1524 mm, six 10x7 targets of 30 mm at 340 mm pitch, 800 mm away,
0.1 px (and, for the six error motions, a second row of 15 mm targets 300 mm nearer). Prints, in this
process: the line model's solve (init, LM, sigmas), the full-pose model's solve, and cv2.calibrateCamera
(intrinsics fixed at the truth as a guess, the targets' points in the world frame) on the same corners;
the ratios are the figures to watch. Target: the line model's solve well under 1 s (the whole
`lps estimate` must stay under 2 s).

Run: .venv/bin/python benchmarks/bench_targets.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from bench_estimate import best_time  # noqa: E402  (run from benchmarks/: its folder is on sys.path)

from lps_gui.blas_threads import limit_blas_threads

limit_blas_threads()  # as lps does, before numpy loads

import cv2  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "core"))
from test_error_motions import CAMERA, two_depth_scene  # noqa: E402
from test_target_model import PAPER_CAMERA, paper_x_axis  # noqa: E402

from lps_gui.core.models.pose_model import solve_poses  # noqa: E402
from lps_gui.core.models.target_model import solve_targets  # noqa: E402


def calibrate_time(obs, layout, intrinsics) -> float:
    _, world, _ = layout.points()
    objp, imgp = [], []
    for uv in obs.corners_px:
        ok = np.isfinite(uv[:, 0])
        if ok.sum() >= 6:
            objp.append(world[ok].astype(np.float32))
            imgp.append(uv[ok].astype(np.float32))
    flags = cv2.CALIB_USE_INTRINSIC_GUESS
    t0 = time.perf_counter()
    cv2.calibrateCamera(objp, imgp, intrinsics.image_size, intrinsics.camera_matrix.copy(), intrinsics.dist.copy(),
                        flags=flags)
    return time.perf_counter() - t0


def main() -> int:
    obs, layout, _ = paper_x_axis(0)
    t_line, sol = best_time(lambda: solve_targets(obs, PAPER_CAMERA), 3)
    t_cv = calibrate_time(obs, layout, PAPER_CAMERA)
    n = int(np.isfinite(obs.corners_px[..., 0]).sum())
    print(f"row, 121 stops, 6 targets, {n} corners: line model {t_line:.3f} s ({sol.iterations} iterations), "
          f"cv2.calibrateCamera {t_cv:.3f} s, ratio {t_line / t_cv:.2f}")
    obs2, truth = two_depth_scene(0)
    t_pose, _ = best_time(lambda: solve_poses(obs2, CAMERA), 2)
    t_cv2 = calibrate_time(obs2, truth["layout"], CAMERA)
    n2 = int(np.isfinite(obs2.corners_px[..., 0]).sum())
    print(f"two depths, 121 stops, 16 targets, {n2} corners: full-pose model {t_pose:.3f} s, "
          f"cv2.calibrateCamera {t_cv2:.3f} s, ratio {t_pose / t_cv2:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
