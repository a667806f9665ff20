"""The lens-model uncertainty of poses from one target plane (issue 35).

A smooth angle profile from one plane is indistinguishable from a lens-model
error that varies across the image as the target moves through it (SPEC 15):
a misfit of a few hundredths of a pixel fakes hundreds of urad of pitch and
yaw. Here the misfit the data allow is a prior on OpenCV's rational and
thin-prism terms (the 7 terms the session's model lacks, :data:`HIGHER_NAMES`),
less what a 5-coefficient calibration of the whole image takes out of them;
each term's standard deviation is the size that alone would leave ``misfit_px``
RMS over the image. Every view's pose absorbs its share of that pixel field by
least squares, so each pose carries a 6x7 sensitivity ``G``; a figure linear in
the poses (an error motion) gets the covariance ``(w g)(w g)^T`` with
``g = grad . G . sd``: correlated over the stops, a smooth profile, which the
resolution rule then does not call resolved unless it stands above it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, higher_rows, project, project_parts

N_HIGHER = 7


@dataclass(frozen=True)
class LensMisfit:
    """Pose sensitivities to the unmodelled lens terms and the prior on those terms."""

    misfit_px: float  # the RMS misfit over the image the prior stands for
    sensitivity: np.ndarray  # (K, 6, 7): d (rotation, translation) of each view / d term (camera frame, left)
    term_sigma: np.ndarray  # (7,): prior sd of each term

    def functional(self, grad: np.ndarray, weights: np.ndarray, unit: float) -> np.ndarray:
        """(m, 7) factor F of the lens covariance F F^T of the figures ``weights @ (grad . v)`` (grad (K, 6))."""
        g = np.einsum("kp,kpj->kj", np.nan_to_num(grad), self.sensitivity) * self.term_sigma
        return unit * (np.asarray(weights, float) @ g)


def _rays(intr: CameraIntrinsics, grid: tuple[int, int] = (16, 12)) -> np.ndarray:
    from lps_gui.core.intrinsics.crossval import pixel_grid, unproject

    rays = unproject(pixel_grid(intr.image_size, grid).reshape(-1, 2), intr)
    return rays[np.all(np.isfinite(rays), axis=1)]


def _higher_jacobian(x_cam: np.ndarray, intr: CameraIntrinsics) -> np.ndarray:
    """d uv / d the 7 higher terms at camera-frame points (M, 3): shape (M, 2, 7)."""
    parts = project_parts(x_cam[:, 0], x_cam[:, 1], x_cam[:, 2], intr)
    Ju, Jv = higher_rows(parts, intr)
    return np.stack([Ju.T, Jv.T], axis=1)


def calibrated_basis(intr: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """(L (9, 7), refit RMS (7,)): the 9 intrinsics a whole-image 5-coefficient fit moves per unit higher term,
    and what each unit term leaves over the image after that fit (px)."""
    rays = _rays(intr)
    J9 = project(rays, intr, want_intrinsics_jacobian=True).d_uv_d_intrinsics.reshape(-1, 9)
    Jh = _higher_jacobian(rays, intr).reshape(-1, N_HIGHER)
    L = np.linalg.lstsq(J9, Jh, rcond=None)[0]
    left = (Jh - J9 @ L).reshape(-1, 2, N_HIGHER)
    return L, np.sqrt(np.mean(np.sum(left**2, axis=1), axis=0))


def lens_misfit(R: np.ndarray, t: np.ndarray, world_points: np.ndarray, seen: np.ndarray, used: np.ndarray,
                intr: CameraIntrinsics, misfit_px: float) -> LensMisfit | None:
    """The poses' sensitivity to a lens misfit of ``misfit_px`` RMS over the image (None when it is 0).

    ``R, t`` (K, 3, 3), (K, 3): camera from world; ``world_points`` (N, 3); ``seen`` (K, N) which corners each
    view saw; ``used`` (K,).
    """
    if not misfit_px > 0:
        return None
    L, per_unit = calibrated_basis(intr)
    K = len(R)
    G = np.zeros((K, 6, N_HIGHER))
    for k in np.flatnonzero(used):
        W = world_points[seen[k]]
        if len(W) < 4:
            continue
        RW = W @ R[k].T
        x = RW + t[k]
        proj = project(x, intr, want_jacobian=True, want_intrinsics_jacobian=True)
        dP = proj.d_uv_d_xcam
        Jv = np.concatenate([-np.cross(dP, RW[:, None, :]), dP], axis=2).reshape(-1, 6)
        E = (_higher_jacobian(x, intr) - proj.d_uv_d_intrinsics @ L).reshape(-1, N_HIGHER)
        G[k] = np.linalg.lstsq(Jv, E, rcond=None)[0]
    return LensMisfit(float(misfit_px), G, float(misfit_px) / np.maximum(per_unit, 1e-300))


@dataclass(frozen=True)
class HeldIntrinsicsError:
    """The poses' sensitivity to the held intrinsics (K, 6, 9) and a factor F (9, r) of a covariance F F^T of
    theirs: the lens-model error the calibration measured (:mod:`lps_gui.core.intrinsics.model_error`), a common
    error of every stop's pose that tilts the angle profiles like the misfit above."""

    sensitivity: np.ndarray
    factor: np.ndarray

    def functional(self, grad: np.ndarray, weights: np.ndarray, unit: float) -> np.ndarray:
        """(m, r) factor of the covariance of the figures ``weights @ (grad . v)``, as :meth:`LensMisfit.functional`."""
        g = np.einsum("kp,kpi->ki", np.nan_to_num(grad), np.nan_to_num(self.sensitivity)) @ self.factor
        return unit * (np.asarray(weights, float) @ g)


@dataclass(frozen=True)
class LensTerms:
    """Independent lens-model terms together: their factors side by side."""

    terms: tuple  # of LensMisfit / HeldIntrinsicsError

    def functional(self, grad: np.ndarray, weights: np.ndarray, unit: float) -> np.ndarray:
        return np.concatenate([t.functional(grad, weights, unit) for t in self.terms], axis=1)


def held_intrinsics_error(sensitivity: np.ndarray | None, covariance: np.ndarray | None) -> HeldIntrinsicsError | None:
    """The term for a model-error covariance (9, 9) of the held intrinsics, None when either is missing or zero."""
    if sensitivity is None or covariance is None or not np.any(covariance):
        return None
    lam, V = np.linalg.eigh((np.asarray(covariance, float) + np.asarray(covariance, float).T) / 2)
    keep = lam > 0
    return HeldIntrinsicsError(np.asarray(sensitivity, float), V[:, keep] * np.sqrt(lam[keep]))


LensTerm = LensMisfit | HeldIntrinsicsError | LensTerms  # anything with ``functional(grad, weights, unit)``


def combined(*terms: LensTerm | None) -> LensTerm | None:
    """The lens terms that are not None, as one (None when none is)."""
    present = tuple(t for t in terms if t is not None)
    return None if not present else present[0] if len(present) == 1 else LensTerms(present)
