"""Planning a rig before any capture: does the board stay in view, and what sigma to expect.

From the lens, the sensor, the board, the camera distance and the plan, we
build the nominal rig (camera facing the board, the board centre seen at
mid-travel), project the board at every target and compute the Cramér-Rao
bound of every position under the model the estimator uses (1-D line or
plane), for a given corner noise. Users choose the camera distance from it:
closer gives a larger board image and smaller sigma, until the board leaves
the view at the ends of the travel.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_board
from lps_gui.core.metrology.iso230_run import JsonDataclass
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError

EDGE_MARGIN_PX = 10.0  # corners closer to the image edge than this are not trusted to be detected


@dataclass
class RigPrediction(JsonDataclass):
    """What a capture with this rig and plan will see and measure."""

    axes: list[str]
    distance_mm: float
    n_targets: int
    board_in_view: bool  # every corner at least EDGE_MARGIN_PX inside the image at every target
    targets_losing_board: int  # targets where some corner leaves the view
    first_target_losing_board: list[float] | None
    min_corner_fraction: float  # smallest fraction of corners in view over all targets
    board_size_px: list[float]  # extent of the board image at mid-travel (w, h)
    sigma_um_median: float | None  # predicted 1-sigma of a position (per coordinate), noise only
    sigma_um_max: float | None
    noise_px: float
    notes: list[str] = field(default_factory=list)


def intrinsics_from_lens(focal_mm: float, pixel_um: float, image_size: tuple[int, int],
                         dist: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)) -> CameraIntrinsics:
    """A pinhole camera from the lens focal length and the pixel pitch, principal point centred."""
    if not (focal_mm > 0 and pixel_um > 0 and image_size[0] > 0 and image_size[1] > 0):
        raise InputError("plan-rig: focal length, pixel size and image size must be positive")
    f_px = focal_mm / (pixel_um * 1e-3)
    w, h = image_size
    return CameraIntrinsics.from_values((int(w), int(h)), f_px, f_px, (w - 1) / 2.0, (h - 1) / 2.0, dist=dist)


def predict_rig(board: Board, intrinsics: CameraIntrinsics, distance_mm: float, plan: Plan,
                noise_px: float = 0.1) -> RigPrediction:
    """Project the board along the plan and compute the Cramér-Rao bound of every position."""
    if not distance_mm > 0:
        raise InputError(f"plan-rig: the camera distance must be positive, got {distance_mm}")
    if not noise_px > 0:
        raise InputError(f"plan-rig: the corner noise must be positive, got {noise_px}")
    planar = plan.planar
    X = board.object_points()
    if planar:
        from lps_gui.core.truth.rig import Rig
        from lps_gui.core.truth.stage_errors import PlanarTruePose

        targets = plan.targets()
        centre = (0.5 * (targets[:, 0].min() + targets[:, 0].max()), 0.5 * (targets[:, 1].min() + targets[:, 1].max()))
        rig = Rig.facing_board(board, intrinsics, distance_mm, centre, planar=True)
        K = targets.shape[0]
        R, t = rig.camera_poses(PlanarTruePose(targets, np.zeros(K), np.zeros((K, 3))))
        mid = rig.camera_poses(PlanarTruePose(np.array([centre]), np.zeros(1), np.zeros((1, 3))))
    else:
        from lps_gui.core.truth.rig import Rig
        from lps_gui.core.truth.stage_errors import TruePose

        targets = plan.targets()[:, None]
        rig1 = Rig.facing_board(board, intrinsics, distance_mm, (float(targets[0, 0]), float(targets[-1, 0])))
        K = targets.shape[0]
        R, t = rig1.camera_poses(TruePose(targets[:, 0], np.zeros((K, 2)), np.zeros((K, 3))))
        c = 0.5 * (targets[0, 0] + targets[-1, 0])
        mid = rig1.camera_poses(TruePose(np.array([c]), np.zeros((1, 2)), np.zeros((1, 3))))
    uv = project_board(R, t, X, intrinsics)  # shape (K, N, 2)
    w, h = intrinsics.image_size
    m = EDGE_MARGIN_PX
    inside = (uv[..., 0] >= m) & (uv[..., 0] <= w - 1 - m) & (uv[..., 1] >= m) & (uv[..., 1] <= h - 1 - m)
    inside &= (np.einsum("kij,nj->kni", R, X) + t[:, None, :])[..., 2] > 0
    frac = inside.mean(axis=1)
    losing = np.flatnonzero(frac < 1.0)
    uv_mid = project_board(mid[0], mid[1], X, intrinsics)[0]
    notes: list[str] = []
    sig_med = sig_max = None
    full = frac == 1.0
    if full.sum() >= 3:  # a chessboard is detected whole or not at all: the other stops measure nothing
        sig = _crb_sigma_um(rig if planar else rig1, planar, targets[full], R[full], t[full], X, inside[full],
                            intrinsics, noise_px)
        sig_med, sig_max = float(np.median(sig[1:])), float(np.max(sig[1:]))
    else:
        notes.append("fewer than 3 targets see the whole board: no sigma predicted; move the camera back")
    if losing.size:
        notes.append(leaves_view_note(losing.size, K, targets, full))
    return RigPrediction(
        axes=["X", "Y"] if planar else ["X"], distance_mm=float(distance_mm), n_targets=int(K),
        board_in_view=bool(losing.size == 0), targets_losing_board=int(losing.size),
        first_target_losing_board=None if not losing.size else [float(v) for v in targets[losing[0]]],
        min_corner_fraction=float(frac.min()), board_size_px=[float(np.ptp(uv_mid[:, 0])), float(np.ptp(uv_mid[:, 1]))],
        sigma_um_median=sig_med, sigma_um_max=sig_max, noise_px=float(noise_px), notes=notes,
    )


def leaves_view_note(losing: int, n_stops: int, targets: np.ndarray, full: np.ndarray) -> str:
    """One line: where the board leaves the view, and the row of targets that measures the whole travel."""
    travel = np.ptp(targets, axis=0)
    covered = np.ptp(targets[full], axis=0) if full.any() else np.zeros_like(travel)
    row = f"--travel {travel[0]:g}" + (f" --travel-y {travel[1]:g}" if len(travel) == 2 else "")
    span = " x ".join(f"{v:.0f}" for v in covered)
    stitch = (f", move this board along in segments of {int(full.sum())} stops (lps capture --segment-stops "
              f"{int(full.sum())})" if len(travel) == 1 and full.sum() >= 4 else "")
    return (f"the board leaves the view at {losing} of {n_stops} targets (it stays whole in view over {span} mm of "
            f"the travel): measure the whole travel against a row of targets (lps plan-rig {row} --sigma-um S, "
            f"same camera){stitch} or move the camera back")


def _crb_sigma_um(rig: Any, planar: bool, targets: np.ndarray, R: np.ndarray, t: np.ndarray, X: np.ndarray,
                  inside: np.ndarray, intrinsics: CameraIntrinsics, noise_px: float) -> np.ndarray:
    """Per-position Cramér-Rao sigma (um) under the estimator's model, gauge at the first target.

    For a plane, the RMS of the two coordinates' sigmas.
    """
    corners = project_board(R, t, X, intrinsics)
    mask = inside
    free = np.ones(targets.shape[0], bool)
    free[0] = False
    if planar:
        from lps_gui.core.models.planar_model import linearize_planar, plane_inverse
        from lps_gui.core.truth.simulate import nominal_planar_state

        st = nominal_planar_state(rig, targets - targets[0])
        st.l0 = st.l0 + st.basis @ targets[0]
        eq, _ = linearize_planar(st, X, corners, mask)
        inv = plane_inverse(eq.A, eq.B, eq.D, free)
        var = np.einsum("kii->ki", inv.cov_view())
        return 1e3 * noise_px * np.sqrt(var.mean(axis=1))
    from lps_gui.core.models.joint_lm import LpsState, line_inverse, linearize

    s = targets[:, 0] - targets[0, 0]
    C0 = rig.C0_board + targets[0, 0] * rig.u_board
    st = LpsState(rig.R_cam_board, -rig.R_cam_board @ C0, -rig.R_cam_board @ rig.u_board, s, intrinsics)
    eq, _ = linearize(st, X, corners, mask)
    inv = line_inverse(eq.A, eq.B, eq.D, free)
    return 1e3 * noise_px * np.sqrt(inv.variances()[:, 0])
