"""6-DOF per position (SPEC 4.5): straightness and angular error motions.

Each view's pose is refined on its own (fixed intrinsics), all views at once:
the per-view normal equations are 6x6 (:mod:`lps_gui.core.numerics.pose_normals`) and
solved batched. The camera centres
C_i = -R_i^T t_i give straightness as their distance from a least-squares
line in the two perpendicular directions (v1, v2) of the motion frame; the
rotation of R_i against the common R, expressed in (u, v1, v2), gives roll,
pitch and yaw. Sigmas come from each view's 6x6 covariance.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3, log_so3, skew
from lps_gui.core.models.lps_model import motion_frame
from lps_gui.core.numerics.pose_normals import PoseNormals, pose_normals


@dataclass
class ViewPoses:
    R: np.ndarray  # shape (K, 3, 3) R_cam_board
    t: np.ndarray  # shape (K, 3) mm
    cov_unit: np.ndarray  # shape (K, 6, 6): (w, t) covariance per unit noise variance
    ssr: np.ndarray  # shape (K,) px^2


@dataclass
class SixDof:
    straightness_um: np.ndarray  # shape (K, 2): along v1, v2
    straightness_sigma_um: np.ndarray  # shape (K, 2)
    angles_urad: np.ndarray  # shape (K, 3): roll (u), pitch (v1), yaw (v2)
    angles_sigma_urad: np.ndarray  # shape (K, 3)
    frame: np.ndarray  # shape (3, 3): (u, v1, v2) columns, board frame
    poses: ViewPoses | None = None  # the per-view poses behind the figures (SPEC 14's error motions start here)
    sigma2_px: float = 0.0  # the noise variance the sigmas are scaled with


def refine_view_poses(
    R0: np.ndarray,
    t0: np.ndarray,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    intrinsics: CameraIntrinsics,
    iterations: int = 3,
    start: PoseNormals | None = None,
) -> ViewPoses:
    """Batched Gauss-Newton on every view's pose (left-perturbed rotation, translation).

    Started from the common model, 3 iterations converge to 1e-6 um on the
    paper rig (quadratic convergence from a close start); more cost time only.
    Each view's 6x6 normal equations come from :func:`pose_normals` and are
    solved batched. ``start``: the blocks at (R0, t0) when the caller has
    them already (the constant-orientation fit starts from the same poses).
    """
    R = np.array(np.broadcast_to(R0, (len(t0), 3, 3)), dtype=float)
    t = np.array(t0, dtype=float)
    eye = 1e-12 * np.eye(6)
    pn = start
    for it in range(iterations + 1):
        if pn is None:
            pn = pose_normals(R, t, X, corners, mask, intrinsics)
        if it == iterations:
            break
        delta = -np.linalg.solve(pn.H + eye, pn.g[..., None])[..., 0]
        R = exp_so3(delta[:, :3]) @ R
        t = t + delta[:, 3:]
        pn = None
    return ViewPoses(R, t, np.linalg.inv(pn.H + eye), pn.ssr)


def six_dof_motion(poses: ViewPoses, R_common: np.ndarray, valid: np.ndarray, sigma2_px: float) -> SixDof:
    """Straightness and angular errors of every view, relative to the valid views' line and R."""
    C = -np.einsum("kji,kj->ki", poses.R, poses.t)  # camera centres, board frame, shape (K, 3)
    Cv = C[valid]
    centre = Cv.mean(axis=0)
    u = np.linalg.svd(Cv - centre, full_matrices=False)[2][0]
    frame = motion_frame(R_common, u)
    if np.dot(frame[:, 0], Cv[-1] - Cv[0]) < 0:  # keep u along the capture order
        frame = motion_frame(R_common, -u)
    F_perp = frame[:, 1:]  # shape (3, 2)
    straight_um = 1e3 * (C - centre) @ F_perp
    # dC/dw = -R^T [t]x, dC/dt = -R^T
    Rt = np.transpose(poses.R, (0, 2, 1))
    dC = np.concatenate([-Rt @ skew(poses.t), -Rt], axis=2)  # shape (K, 3, 6)
    Js = np.einsum("ia,kib->kab", F_perp, dC)  # shape (K, 2, 6)
    cov = sigma2_px * poses.cov_unit
    straight_sigma_um = 1e3 * np.sqrt(np.einsum("kab,kbc,kac->ka", Js, cov, Js))
    Q = np.einsum("kji,jl->kil", poses.R, R_common)  # R_i^T R
    angles_urad = 1e6 * log_so3(Q) @ frame
    Ja = -np.einsum("ia,kji->kaj", frame, poses.R)  # d angles / d w = -F^T R_i^T, shape (K, 3, 3)
    angles_sigma_urad = 1e6 * np.sqrt(np.einsum("kab,kbc,kac->ka", Ja, cov[:, :3, :3], Ja))
    return SixDof(straight_um, straight_sigma_um, angles_urad, angles_sigma_urad, frame, poses, float(sigma2_px))
