"""A camera moving past fixed targets (SPEC 13): the geometry the simulator and the planner share.

World frame = target 0's frame. The camera keeps one orientation R; its
translation is t_i = l0 + N s_i (N: 3 x D, the motion directions in the camera
frame, D = 1 for a line, 2 for a plane), and target j's corner X is seen at
x_cam = R (Q_j X + p_j) + t_i. Pure math: no files, no images.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.targets import Target


@dataclass(frozen=True)
class TargetLayout:
    """Targets and their mounting poses in the world (target 0's) frame: X_w = Q_j X + p_j."""

    targets: tuple[Target, ...]
    Q: np.ndarray  # (T, 3, 3)
    p: np.ndarray  # (T, 3) mm

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every target's corners laid end to end: own-frame X (N, 3), world X_w (N, 3), target index (N,)."""
        own = np.concatenate([t.board.object_points() for t in self.targets])
        which = np.repeat(np.arange(len(self.targets)), [t.board.n_corners for t in self.targets])
        world = np.einsum("nij,nj->ni", self.Q[which], own) + self.p[which]
        return own, world, which


def row_layout(
    targets: list[Target], pitch_mm: float, tilt_sigma_rad: float = 0.0, offset_sigma_mm: float = 0.0,
    depth_mm: np.ndarray | None = None, seed: int = 0,
) -> TargetLayout:
    """Targets in a row along x of target 0 at ``pitch_mm``, each mounted with small random errors.

    ``depth_mm`` (T,) moves targets along -z of target 0 (towards a camera looking at its front): a
    two-depth constellation. Target 0 defines the world frame, so it has no mounting error.
    """
    rng = np.random.default_rng(seed)
    T = len(targets)
    Q = np.stack([np.eye(3)] + [exp_so3(rng.normal(0.0, tilt_sigma_rad, 3)) for _ in range(T - 1)])
    p = np.zeros((T, 3))
    p[:, 0] = pitch_mm * np.arange(T)
    p[1:] += rng.normal(0.0, offset_sigma_mm, (T - 1, 3))
    if depth_mm is not None:
        p[:, 2] -= np.asarray(depth_mm, float)
    return TargetLayout(tuple(targets), Q, p)


def two_depth_layout(
    far: list[Target], near: list[Target], far_pitch_mm: float, near_pitch_mm: float, depth_mm: float,
    near_offset_mm: tuple[float, float], tilt_sigma_rad: float = 0.0, offset_sigma_mm: float = 0.0, seed: int = 0,
) -> TargetLayout:
    """A far row and, ``depth_mm`` nearer the camera, a near row of (smaller) targets: a two-depth constellation.

    A rotation of the camera moves near and far corners alike in the image, a
    translation in proportion to 1/depth, so the two rows separate the tilts
    from the translations (SPEC 14). The far row is laid out as
    :func:`row_layout`; the near row starts at ``near_offset_mm`` (x, y) in target
    0's frame (y: beside the far row in the image, so that it hides little of
    it) and runs along x at ``near_pitch_mm``. ``depth_mm=0`` puts both rows in
    one plane (the tilts then stay unresolved). Every target but target 0
    gets the random mounting errors.
    """
    T = len(far) + len(near)
    base = row_layout(list(far) + list(near), 0.0, tilt_sigma_rad, offset_sigma_mm, seed=seed)
    nominal = np.zeros((T, 3))
    nominal[: len(far), 0] = far_pitch_mm * np.arange(len(far))
    nominal[len(far):, 0] = near_offset_mm[0] + near_pitch_mm * np.arange(len(near))
    nominal[len(far):, 1] = near_offset_mm[1]
    nominal[len(far):, 2] = -float(depth_mm)
    return TargetLayout(base.targets, base.Q, base.p + nominal)


def occluded(layout: TargetLayout, R: np.ndarray, t: np.ndarray, world: np.ndarray, which: np.ndarray,
             margin_squares: float = 0.5) -> np.ndarray:
    """(K, N) corners hidden behind another target's paper (a nearer row of a two-depth constellation).

    ``R`` (3, 3) or (K, 3, 3), ``t`` (K, 3): camera from world. A corner is hidden when the segment from
    the camera centre to it crosses another target's plane inside that target's paper.
    """
    Rk = np.broadcast_to(R, (len(t), 3, 3))
    C = -np.einsum("kji,kj->ki", Rk, t)  # camera centres in the world
    hidden = np.zeros((len(t), len(world)), bool)
    ray = world[None, :, :] - C[:, None, :]  # (K, N, 3)
    for k, tgt in enumerate(layout.targets):
        n = layout.Q[k][:, 2]
        denom = ray @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = ((layout.p[k] - C) @ n)[:, None] / denom
        cross = (lam > 0) & (lam < 1 - 1e-9) & (which[None, :] != k)
        if not cross.any():
            continue
        hit = C[:, None, :] + lam[..., None] * ray - layout.p[k]
        local = hit @ layout.Q[k]  # in target k's frame
        s, m = tgt.board.square_mm, 1.0 + margin_squares
        inside = ((local[..., 0] > -m * s) & (local[..., 0] < (tgt.board.cols - 1 + m) * s)
                  & (local[..., 1] > -m * s) & (local[..., 1] < (tgt.board.rows - 1 + m) * s))
        hidden |= cross & inside
    return hidden


def field_radius2(intrinsics: CameraIntrinsics) -> float:
    """The squared normalized radius (x/z)^2 + (y/z)^2 up to which the radial distortion still grows outwards.

    Beyond its first turning point the OpenCV polynomial folds points from far outside the field of view
    back into the image (the paper's lens at about 1.8); no real lens images them, so no corner there is seen.
    """
    k1, k2, _, _, k3 = intrinsics.dist
    r2 = np.linspace(0.0, 100.0, 20001)
    slope = 1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 ** 2 + 7.0 * k3 * r2 ** 3  # d (r radial(r)) / d r
    turning = np.flatnonzero(slope <= 0)
    return float(r2[turning[0]]) if turning.size else float("inf")


def observe(
    layout: TargetLayout, intrinsics: CameraIntrinsics, R: np.ndarray, t: np.ndarray,
    noise_px: float = 0.0, seed: int = 0, border_px: float = 2.0,
) -> np.ndarray:
    """Corners (K, N, 2) of every target seen from camera translations ``t`` (K, 3); NaN where not seen.

    ``R`` is one orientation (3, 3) or one per view (K, 3, 3). A corner is seen when it is in front of
    the camera, inside the lens's field (:func:`field_radius2`) and the image by ``border_px`` and not
    behind another target's paper (the targets face the camera by construction); the noise is Gaussian,
    per coordinate.
    """
    _, world, which = layout.points()
    R = np.asarray(R, float)
    x_cam = (np.einsum("ij,nj->ni", R, world)[None] if R.ndim == 2 else np.einsum("kij,nj->kni", R, world))
    x_cam = x_cam + t[:, None, :]
    uv = project(x_cam, intrinsics).uv
    w, h = intrinsics.image_size
    with np.errstate(divide="ignore", invalid="ignore"):
        r2 = (x_cam[..., 0] ** 2 + x_cam[..., 1] ** 2) / x_cam[..., 2] ** 2
    inside = ((uv[..., 0] >= border_px) & (uv[..., 0] <= w - 1 - border_px)
              & (uv[..., 1] >= border_px) & (uv[..., 1] <= h - 1 - border_px) & (x_cam[..., 2] > 0)
              & (r2 < field_radius2(intrinsics)))
    seen = inside & ~occluded(layout, R, t, world, which)
    rng = np.random.default_rng(seed)
    uv = uv + rng.normal(0.0, noise_px, uv.shape) if noise_px > 0 else uv
    uv[~seen] = np.nan
    return uv
