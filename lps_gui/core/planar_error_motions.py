"""The error motions of both axes of a planar (XY) stage, from every stop's full pose (SPEC 10, 14).

Stage frame: X along the fitted X motion of the camera centre, Y its in-plane
perpendicular towards +Y motion, Z = X x Y. Per stop (relative to the first
usable stop) the rotation of the camera's attitude about X, Y, Z and the
centre's displacement. A gantry's error is each axis' error as a function of
its own position (:class:`~lps_gui.core.stage_errors.PlanarErrorModel`), so
every per-stop figure is fitted on the grid as f(x) + g(y) (least squares,
g = 0 at the reference stop's y): the rotation about X as a function of x is
EAX (roll of X), as a function of y EAY (pitch of Y), and so on; positioning
EXX(x) and EYY(y) are the displacements along the axis minus the commanded,
the straightness EYX, EZX (of x) and EXY, EZY (of y) the across-axis parts
with their least-squares line taken out (its slope in the plane is the
squareness, reported with the planar figures). Every figure is linear in the
views' pose perturbations, so its sigma comes from the poses' full covariance
(:meth:`PositionCovariance.weighted_variances`); a profile is resolved by
:func:`lps_gui.core.resolution.profile_span`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.error_motions import _grads
from lps_gui.core.pose_model import PoseSolution
from lps_gui.core.resolution import ProfileSpan, profile_span
from lps_gui.core.rotation import log_so3

# (ISO name, along "X" or "Y", kind, component): kind "angle" (about stage X/Y/Z), "position" (along X/Y/Z)
MOTIONS = (
    ("EXX", 0, "position", 0), ("EYX", 0, "straightness", 1), ("EZX", 0, "straightness", 2),
    ("EAX", 0, "angle", 0), ("EBX", 0, "angle", 1), ("ECX", 0, "angle", 2),
    ("EYY", 1, "position", 1), ("EXY", 1, "straightness", 0), ("EZY", 1, "straightness", 2),
    ("EAY", 1, "angle", 0), ("EBY", 1, "angle", 1), ("ECY", 1, "angle", 2),
)
ANGLE_NAMES = ("EAX", "EBX", "ECX")  # per-stop columns of positions.csv: about the stage X, Y, Z (SPEC 14)


@dataclass
class PlanarErrorMotions:
    frame: np.ndarray  # (3, 3) columns X, Y, Z in the world frame
    reference: int
    per_stop_urad: np.ndarray  # (K, 3): rotation about X, Y, Z from the reference stop
    per_stop_sigma_urad: np.ndarray  # (K, 3)
    axis_positions: dict[int, np.ndarray]  # 0: the x values of the profiles of X, 1: the y values of Y
    values: dict[str, np.ndarray]  # per ISO name, over its axis' positions (um or urad), 0 at the reference's
    sigmas: dict[str, np.ndarray]  # of the values (relative to the reference stop)
    centred_sigmas: dict[str, np.ndarray]  # without the reference stop's own noise (relative to the profile's mean)
    profiles: dict[str, ProfileSpan]
    resolved: dict[str, bool]
    reference_positions: tuple[int, int]  # the reference stop's x among X's positions, its y among Y's


def _plane_frame(C: np.ndarray, xy: np.ndarray, A: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """X along d C / d x, Y the in-plane part of d C / d y perpendicular to it, Z = X x Y."""
    M = np.c_[np.ones(len(rows)), xy[rows] - xy[rows].mean(axis=0)]
    coef = np.linalg.lstsq(M, C[rows], rcond=None)[0]  # (3, 3): offset, d/dx, d/dy
    X = coef[1] / np.linalg.norm(coef[1])
    Y = coef[2] - (coef[2] @ X) * X
    Y /= np.linalg.norm(Y)
    return np.stack([X, Y, np.cross(X, Y)], axis=1)


def _additive(xy: np.ndarray, rows: np.ndarray, ref: int) -> tuple[list[np.ndarray], np.ndarray]:
    """The grid values of x and of y, and the (nx + ny, K) map from per-stop values to f(x) and g(y).

    Least squares of v_i = f(x_i) + g(y_i) over ``rows``; the gauge puts g(y_ref) = 0, and f is
    relative to f(x_ref) as every figure is relative to the reference stop (v_ref = 0).
    """
    K = len(xy)
    keys = [np.unique(np.round(xy[rows, a], 6)) for a in (0, 1)]
    ix = np.searchsorted(keys[0], np.round(xy[rows, 0], 6))
    iy = np.searchsorted(keys[1], np.round(xy[rows, 1], 6))
    nx, ny = len(keys[0]), len(keys[1])
    D = np.zeros((len(rows), nx + ny))
    D[np.arange(len(rows)), ix] = 1.0
    D[np.arange(len(rows)), nx + iy] = 1.0
    gauge = nx + int(np.searchsorted(keys[1], round(float(xy[ref, 1]), 6)))
    keep = np.ones(nx + ny, bool)
    keep[gauge] = False
    W = np.zeros((nx + ny, K))
    W[np.ix_(keep, rows)] = np.linalg.pinv(D[:, keep])
    return keys, W


def planar_error_motions(sol: PoseSolution, targets_mm: np.ndarray) -> PlanarErrorMotions:
    """The 12 error motions of an XY stage and the per-stop angles, with sigmas, from :func:`solve_poses`."""
    used = sol.used
    K = len(used)
    rows = np.flatnonzero(used)
    ref = int(rows[0])
    xy = np.asarray(targets_mm, float).reshape(K, 2)
    C, A, dC, dth = _grads(sol)
    S = _plane_frame(C, xy, A, rows)
    theta = log_so3(np.einsum("kij,lj->kil", A, A[ref]))  # A_i A_ref^T
    theta[ref] = 0.0
    angle = 1e6 * theta @ S  # (K, 3) about X, Y, Z
    pos = 1e3 * (C - C[ref]) @ S  # (K, 3) um along X, Y, Z
    pos[:, :2] -= 1e3 * (xy - xy[ref])
    rel = np.zeros((K, K))
    rel[rows, rows] = 1.0
    rel[rows, ref] -= 1.0
    grads = {"angle": [np.einsum("i,kip->kp", S[:, c], dth) for c in range(3)],
             "position": [np.einsum("i,kip->kp", S[:, c], dC) for c in range(3)]}
    stop_sig = np.stack([np.sqrt(np.maximum(sol.covariance.weighted_variances(rel, g), 0.0)) for g in grads["angle"]],
                        axis=1) * 1e6
    keys, W = _additive(xy, rows, ref)
    nx = len(keys[0])
    parts = {0: slice(0, nx), 1: slice(nx, None)}
    at_ref = (int(np.searchsorted(keys[0], round(float(xy[ref, 0]), 6))),
              int(np.searchsorted(keys[1], round(float(xy[ref, 1]), 6))))
    values, sigmas, centred, profiles = {}, {}, {}, {}
    for name, along, kind, comp in MOTIONS:
        per_stop, unit = (angle[:, comp], 1e6) if kind == "angle" else (pos[:, comp], 1e3)
        grad = grads["angle" if kind == "angle" else "position"][comp]
        w = W[parts[along]]
        if kind == "straightness":  # off the least-squares line over the axis' positions
            M = np.c_[np.ones(len(keys[along])), keys[along]]
            w = (np.eye(len(keys[along])) - M @ np.linalg.pinv(M)) @ w
            wc = w
        else:  # relative to the reference's position; centred: relative to the profile's mean
            wc = w - w.mean(axis=0)
            w = w - w[at_ref[along]]
        values[name] = w @ np.where(used, per_stop, 0.0)
        sigmas[name] = unit * np.sqrt(np.maximum(sol.covariance.weighted_variances(w, grad), 0.0))
        centred[name] = unit * np.sqrt(np.maximum(sol.covariance.weighted_variances(wc, grad), 0.0))
        cov = unit**2 * sol.covariance.weighted_covariance(w, grad) if sol.covariance.shares_targets else None
        profiles[name] = profile_span(values[name], centred[name], keys[along], np.ones(len(keys[along]), bool),
                                      covariance=cov)
    stop_sig[~used] = np.nan
    angle[~used] = np.nan
    return PlanarErrorMotions(S, ref, angle, np.where(used[:, None], stop_sig, np.nan), {0: keys[0], 1: keys[1]},
                              values, sigmas, centred, profiles, {n: bool(p.resolved) for n, p in profiles.items()},
                              at_ref)
