"""results.json ``lens_model`` and its flag: does the lens model fit, and what misfit do the poses carry (issue 35).

Two witnesses of a lens the session's model cannot follow: the intrinsics
calibration's binned residuals (``lens_fit`` in intrinsics.json, written by
`lps intrinsics`) and this session's own residuals under its per-view poses,
binned over the image (:mod:`lps_gui.core.intrinsics.residual_structure`).
The larger misfit is what the poses carry (:mod:`lps_gui.core.metrology.lens_tilts`):
the error motions' sigmas and covariance take it in, so a smooth tilt that the
misfit could fake is not resolved. A misfit above the corner noise is a flag
that names the richer lens model to calibrate.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.intrinsics.residual_structure import RECALIBRATE, ResidualStructure, residual_structure
from lps_gui.core.metrology.lens_tilts import LensMisfit, combined, held_intrinsics_error, lens_misfit
from lps_gui.core.models.pose_model import PoseSolution
from lps_gui.io.intrinsics_file import model_error_covariance
from lps_gui.io.results.sections import Flag


@dataclass
class LensModelCheck:
    misfit: LensMisfit | None  # the poses' sensitivity, None when no misfit is seen
    section: dict[str, Any]  # results.json ``lens_model``
    flags: list[dict[str, Any]] = field(default_factory=list)
    position_sigma_um: np.ndarray | None = None  # (K,) the misfit's share of each board-plane position


def corner_points(obs: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each corner's point in its own target's frame (N, 3) and its target (N,)."""
    if obs.mounted is None:
        X = obs.board.object_points()
        return X, np.zeros(len(X), int)
    from lps_gui.core.models.target_model import TargetObservations

    tobs = TargetObservations(list(obs.mounted), obs.corners_px, obs.targets, list(obs.names))
    return tobs.own_points, tobs.which


def session_structure(sol: PoseSolution, own: np.ndarray, which: np.ndarray, corners_px: np.ndarray,
                      intr: CameraIntrinsics) -> ResidualStructure | None:
    """The session's residuals under its poses, binned over the image."""
    W = np.einsum("nij,nj->ni", sol.Q[which], own) + sol.p[which]
    x = np.einsum("kij,nj->kni", sol.R, W) + sol.t[:, None, :]
    res = corners_px - project(x, intr).uv
    res[~np.asarray(sol.used, bool)] = np.nan
    row_of = np.unique(np.c_[which, np.round(own[:, 1], 6)], axis=0, return_inverse=True)[1].ravel()
    return residual_structure(np.where(np.isfinite(res), corners_px, np.nan), res, intr.image_size, row_of)


def _significant(record: dict[str, Any] | None) -> bool:
    """A recorded residual structure (intrinsics.json ``lens_fit``) is beyond noise (at the check's P_VALUE)."""
    from lps_gui.core.intrinsics.residual_structure import P_VALUE
    from lps_gui.core.metrology.resolution import chi2_sf

    try:
        return bool(record) and int(record["dof"]) > 0 and chi2_sf(float(record["chi2"]), int(record["dof"])) < P_VALUE
    except (KeyError, TypeError, ValueError):
        return False


def lens_model_check(sol: PoseSolution, obs: Any, intrinsics: Any = None) -> LensModelCheck:
    """The lens-model section, its flags, and the misfit the poses carry; ``intrinsics``: those the poses were
    solved with (self-calibrated), else the session's."""
    intr = intrinsics or obs.intrinsics
    own, which = corner_points(obs)
    session = session_structure(sol, own, which, obs.corners_px, intr)
    extra = obs.intrinsics.extra  # the calibration's own record travels with the session's intrinsics
    calibration = extra.get("lens_fit") if isinstance(extra.get("lens_fit"), dict) else None
    cal_misfit = float(calibration.get("misfit_px") or 0.0) if calibration else 0.0
    # a misfit counts only where the residuals are structured beyond noise: a calibration of a lens the model fits
    # still shows a few thousandths of a pixel by chance, which would inflate every tilt's sigma for nothing
    misfit_px = max(cal_misfit if _significant(calibration) else 0.0,
                    session.misfit_px if session is not None and session.significant else 0.0)
    flags = []
    if calibration and calibration.get("flagged"):
        flags.append(Flag.of(index=None, kind="lens_model", message=(
            f"lens model does not fit the intrinsics calibration: its residuals leave {cal_misfit:.3f} px RMS beyond "
            f"the corner noise of {float(calibration.get('noise_px') or 0):.3f} px, structured over the image; tilts "
            f"from one target plane are then not resolved; {RECALIBRATE}")).to_dict())
    if session is not None and session.exceeds_noise:
        flags.append(Flag.of(index=None, kind="lens_model", message=session.message("this session's views")).to_dict())
    W = np.einsum("nij,nj->ni", sol.Q[which], own) + sol.p[which]
    seen = np.all(np.isfinite(obs.corners_px), axis=-1)
    misfit = lens_misfit(sol.R, sol.t, W, seen, np.asarray(sol.used, bool), intr, misfit_px)
    section = {"misfit_px": misfit_px, "model": "opencv12" if intr.has_higher else "opencv5",
               "calibration": calibration and {**{k: calibration.get(k) for k in ("misfit_px", "noise_px", "flagged")},
                                               "significant": _significant(calibration)},
               "session": None if session is None else {k: v for k, v in session.to_dict().items()
                                                         if k not in ("mean_px", "count")},
               "carried_by_poses": misfit is not None,
               "term_sigma": None if misfit is None else misfit.term_sigma.tolist()}
    return LensModelCheck(misfit, section, flags)


def position_lens_sigma_um(sol: PoseSolution, obs: Any, misfit: LensMisfit, frame_world: np.ndarray,
                           reference: int) -> np.ndarray:
    """Per stop: the lens misfit's 1-sigma on the board-plane position along the motion, relative to the reference (um).

    The board centre seen from the camera, P = R c + t, moves by w x (R c) + dt under a view's perturbation, so the
    position along the motion u (camera frame) has the gradient [(R c) x u, u]: the lens misfit's share of the
    positions, which does not average out over the stops (it is smooth over the image).
    """
    own, which = corner_points(obs)
    centre = np.mean(np.einsum("nij,nj->ni", sol.Q[which], own) + sol.p[which], axis=0)
    u = np.einsum("kij,j->ki", sol.R, frame_world[:, 0])
    grad = np.concatenate([np.cross(np.einsum("kij,j->ki", sol.R, centre), u), u], axis=1)
    K = len(sol.R)
    rel = np.eye(K)
    rel[:, reference] -= 1.0
    rel[reference, reference] = 0.0
    return np.sqrt(np.sum(misfit.functional(grad, rel, 1e3) ** 2, axis=1))


def lens_terms(check: LensModelCheck, sol: PoseSolution, intrinsics: CameraIntrinsics) -> Any:
    """What the error motions' sigmas carry of the lens model: the misfit the poses carry and the model error the
    intrinsics calibration measured (``model_error`` in intrinsics.json) through the poses' sensitivity to them."""
    return combined(check.misfit, held_intrinsics_error(sol.intrinsics_gradient, model_error_covariance(intrinsics)))
