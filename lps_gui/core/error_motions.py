"""The six error motions of an axis at every stop (ISO 230-1 names, SPEC 14), from full camera poses.

Stage frame of one axis: X along the fitted motion of the camera centre, Z the
part of the mean viewing direction perpendicular to X (towards the targets),
Y = Z x X. Per stop, relative to the first usable stop:

- positioning EXX: displacement along X minus the commanded one;
- straightness EYX, EZX: the camera centre's offset across X, off the least-squares line;
- roll EAX, pitch EBX, yaw ECX: the rotation of the camera's attitude (camera-to-target)
  from the first stop, about the stage's X, Y, Z.

Every figure is linear in the views' pose perturbations to first order, so its
sigma is that functional's variance under the poses' full (factored)
covariance; a profile is *resolved* by the one rule of :mod:`core.resolution`, given the motion's
covariance over the stops when they share estimated targets (their errors then correlate).
The Abbe effect at a tool point (an offset from the camera centre, in the
camera frame) turns the angles into the positioning error there.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.pose_model import PoseSolution
from lps_gui.core.resolution import ProfileSpan, profile_span
from lps_gui.core.rotation import log_so3, skew

LINEAR = ("positioning", "straightness_y", "straightness_z")
ANGULAR = ("roll", "pitch", "yaw")


def iso_names(axis: str) -> dict[str, str]:
    """ISO 230-1 names of an axis's six error motions: X -> EXX, EYX, EZX, EAX, EBX, ECX."""
    a = axis.upper()
    others = [c for c in "XYZ" if c != a]
    return {"positioning": f"E{a}{a}", "straightness_y": f"E{others[0]}{a}", "straightness_z": f"E{others[1]}{a}",
            "roll": f"EA{a}", "pitch": f"EB{a}", "yaw": f"EC{a}"}


@dataclass
class ErrorMotions:
    axis: str
    frame: np.ndarray  # (3, 3) columns X, Y, Z of the stage frame in the world (target 0's) frame
    reference: int
    values: dict[str, np.ndarray]  # (K,) each: um for the linear, urad for the angular motions
    sigmas: dict[str, np.ndarray]  # relative to the reference stop
    centred_sigmas: dict[str, np.ndarray]  # without the reference stop's own noise
    single_view_urad: np.ndarray  # (K, 3) sigma of roll, pitch, yaw from each view alone (targets known)
    resolved: dict[str, bool]
    measured_mm: np.ndarray  # (K,) displacement along X from the reference stop
    tool_positioning_um: np.ndarray | None = None  # EXX at the tool point (Abbe), when a tool offset is given
    tool_positioning_sigma_um: np.ndarray | None = None
    names: dict[str, str] = field(default_factory=dict)
    profiles: dict[str, ProfileSpan] = field(default_factory=dict)  # p-v over the targets, its noise p-v
    tool_cam_mm: np.ndarray | None = None  # the tool point's offset from the camera centre, camera frame


def _grads(sol: PoseSolution):
    """Centres C (K, 3), attitudes A (K, 3, 3), and d C / d v, d theta / d v (K, 3, 6)."""
    R, t = sol.R, sol.t
    A = np.swapaxes(R, 1, 2)  # camera-to-world
    C = -np.einsum("kij,kj->ki", A, t)
    dC = np.concatenate([-np.einsum("kij,kjl->kil", A, skew(t)), -A], axis=2)
    dth = np.concatenate([-A, np.zeros_like(A)], axis=2)  # attitude A <- exp(-A w) A for R <- exp(w) R
    return C, A, dC, dth


def _tool_grad(A: np.ndarray, dC: np.ndarray, tool_cam_mm: np.ndarray) -> np.ndarray:
    """d (tool point in the world) / d v (K, 3, 6) for a tool offset fixed in the camera frame."""
    Ao = np.einsum("kij,j->ki", A, tool_cam_mm)
    return dC + np.concatenate([np.einsum("kij,kjl->kil", skew(Ao), A), np.zeros_like(A)], axis=2)


def error_motions(sol: PoseSolution, targets_mm: np.ndarray, axis: str = "X",
                  tool_cam_mm: np.ndarray | None = None, tool_stage_mm: np.ndarray | None = None) -> ErrorMotions:
    """EXX ... ECX of a line axis at every stop, with sigmas, from the poses of :func:`solve_poses`.

    The tool point is an offset from the camera centre fixed to the carriage: in
    the camera frame (``tool_cam_mm``), or in the stage frame at the reference stop
    (``tool_stage_mm``: along X, Y, Z of the axis, as a user measures it).
    """
    used = sol.used
    K = len(used)
    rows = np.flatnonzero(used)
    ref = int(rows[0])
    x = np.asarray(targets_mm, float).reshape(K, -1)[:, 0]
    C, A, dC, dth = _grads(sol)
    Cu = C[used] - C[used].mean(axis=0)
    X = np.linalg.svd(Cu, full_matrices=False)[2][0]
    if (C[rows[-1]] - C[ref]) @ X * (x[rows[-1]] - x[ref]) < 0:
        X = -X
    z = A[used][:, :, 2].mean(axis=0)
    Z = z - (z @ X) * X
    Z /= np.linalg.norm(Z)
    Y = np.cross(Z, X)
    S = np.stack([X, Y, Z], axis=1)
    m = (C - C[ref]) @ X
    # weights of each figure on the views' 6-vectors: rows = stops, columns = views
    rel = np.zeros((K, K))
    rel[rows, rows] = 1.0
    rel[rows, ref] -= 1.0
    fit = np.c_[np.ones(len(rows)), m[rows]]
    hat = fit @ np.linalg.pinv(fit)  # least-squares line over the used stops
    line = np.zeros((K, K))
    line[np.ix_(rows, rows)] = np.eye(len(rows)) - hat
    n = len(rows)
    centred = np.zeros((K, K))
    centred[np.ix_(rows, rows)] = np.eye(n) - 1.0 / n
    values, sig, csig, profiles = {}, {}, {}, {}
    shared = sol.covariance.shares_targets  # a constellation's stops share the targets: correlated errors
    grad_x = np.einsum("i,kip->kp", X, dC)
    comps = {"positioning": (1e3 * (m - (x - x[ref])), grad_x, rel, 1e3)}
    for name, axis_vec in (("straightness_y", Y), ("straightness_z", Z)):
        coord = C @ axis_vec
        resid = np.full(K, np.nan)
        resid[rows] = coord[rows] - hat @ coord[rows]
        comps[name] = (1e3 * resid, np.einsum("i,kip->kp", axis_vec, dC), line, 1e3)
    theta = log_so3(np.einsum("kij,lj->kil", A, A[ref]))  # A_i A_ref^T
    theta[ref] = 0.0  # exactly, not log_so3's rounding
    for k, name in enumerate(ANGULAR):
        comps[name] = (1e6 * theta @ S[:, k], np.einsum("i,kip->kp", S[:, k], dth), rel, 1e6)
    for name, (val, grad, weights, unit) in comps.items():
        val = np.where(used, val, np.nan)
        values[name] = val
        var = sol.covariance.weighted_variances(weights, grad)
        sig[name] = np.where(used, unit * np.sqrt(np.maximum(var, 0.0)), np.nan)
        var = sol.covariance.weighted_variances(centred if name in ANGULAR or name == "positioning" else line, grad)
        csig[name] = np.where(used, unit * np.sqrt(np.maximum(var, 0.0)), np.nan)
        cov = unit**2 * sol.covariance.weighted_covariance(weights, grad) if shared else None
        profiles[name] = profile_span(val, csig[name], x, used, covariance=cov)
    single = np.full((K, 3), np.nan)
    for i in rows:
        Om = sol.single_view[i, 0:3, 0:3]
        cov_world = A[i] @ Om @ A[i].T
        single[i] = 1e6 * np.sqrt(np.diag(S.T @ cov_world @ S))
    resolved = {name: bool(prof.resolved) for name, prof in profiles.items()}
    tool = tool_sig = None
    if tool_stage_mm is not None:
        tool_cam_mm = sol.R[ref] @ S @ np.asarray(tool_stage_mm, float)
    if tool_cam_mm is not None:
        tool_cam_mm = np.asarray(tool_cam_mm, float)
        dtool = _tool_grad(A, dC, tool_cam_mm)
        T_world = C + np.einsum("kij,j->ki", A, tool_cam_mm)
        tool = np.where(used, 1e3 * ((T_world - T_world[ref]) @ X - (x - x[ref])), np.nan)
        var = sol.covariance.weighted_variances(rel, np.einsum("i,kip->kp", X, dtool))
        tool_sig = np.where(used, 1e3 * np.sqrt(np.maximum(var, 0.0)), np.nan)
    return ErrorMotions(axis, S, ref, values, sig, csig, single, resolved, m, tool, tool_sig, iso_names(axis),
                        profiles, tool_cam_mm)
