"""The six error motions of an axis at every stop (ISO 230-1 names, SPEC 14), from full camera poses;
of both axes of an XY stage (D = 2) at the end of this module.

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

from lps_gui.core.geometry.rotation import log_so3, skew
from lps_gui.core.metrology.lens_tilts import LensTerm
from lps_gui.core.metrology.resolution import ProfileSpan, profile_span
from lps_gui.core.models.pose_model import PoseSolution

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


def _functional_sigmas(sol: PoseSolution, grad: np.ndarray, w: np.ndarray, wc: np.ndarray, unit: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Sigmas of the figures ``w`` @ per-stop values (weights (m, K) on one gradient (K, 6)) and of their centred
    form ``wc``, and their full covariance when the stops share estimated targets (their errors then correlate)."""
    c = sol.covariance
    sigma = unit * np.sqrt(np.maximum(c.weighted_variances(w, grad), 0.0))
    centred = unit * np.sqrt(np.maximum(c.weighted_variances(wc, grad), 0.0))
    return sigma, centred, unit**2 * c.weighted_covariance(w, grad) if c.shares_targets else None


def _tool_grad(A: np.ndarray, dC: np.ndarray, tool_cam_mm: np.ndarray) -> np.ndarray:
    """d (tool point in the world) / d v (K, 3, 6) for a tool offset fixed in the camera frame."""
    Ao = np.einsum("kij,j->ki", A, tool_cam_mm)
    return dC + np.concatenate([np.einsum("kij,kjl->kil", skew(Ao), A), np.zeros_like(A)], axis=2)


def _with_lens(sol: PoseSolution, lens: LensTerm | None, grad: np.ndarray, w: np.ndarray, wc: np.ndarray,
               unit: float, sigmas: tuple[np.ndarray, np.ndarray, np.ndarray | None]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """:func:`_functional_sigmas`' sigmas and covariance with the lens-model term added (correlated over the stops)."""
    s, c, cov = sigmas
    if lens is None:
        return s, c, cov
    Fw, Fc = lens.functional(grad, w, unit), lens.functional(grad, wc, unit)
    if cov is None:
        cov = unit**2 * sol.covariance.weighted_covariance(w, grad)
    return (np.sqrt(s**2 + np.sum(Fw**2, axis=1)), np.sqrt(c**2 + np.sum(Fc**2, axis=1)), cov + Fw @ Fw.T)


def error_motions(sol: PoseSolution, targets_mm: np.ndarray, axis: str = "X",
                  tool_cam_mm: np.ndarray | None = None, tool_stage_mm: np.ndarray | None = None,
                  lens: LensTerm | None = None) -> ErrorMotions:
    """EXX ... ECX of a line axis at every stop, with sigmas, from the poses of :func:`solve_poses`.

    The tool point is an offset from the camera centre fixed to the carriage: in
    the camera frame (``tool_cam_mm``), or in the stage frame at the reference stop
    (``tool_stage_mm``: along X, Y, Z of the axis, as a user measures it). ``lens``: the poses'
    sensitivity to the lens misfit the data allow (:mod:`lps_gui.core.metrology.lens_tilts`), whose
    smooth, correlated effect every figure's sigma and covariance then carry.
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
        wc = centred if name in ANGULAR or name == "positioning" else line
        s, c, cov = _with_lens(sol, lens, grad, weights, wc, unit, _functional_sigmas(sol, grad, weights, wc, unit))
        sig[name], csig[name] = np.where(used, s, np.nan), np.where(used, c, np.nan)
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
        g_tool = np.einsum("i,kip->kp", X, dtool)
        var = sol.covariance.weighted_variances(rel, g_tool)
        if lens is not None:
            var = var + np.sum(lens.functional(g_tool, rel, 1.0) ** 2, axis=1)
        tool_sig = np.where(used, 1e3 * np.sqrt(np.maximum(var, 0.0)), np.nan)
    return ErrorMotions(axis, S, ref, values, sig, csig, single, resolved, m, tool, tool_sig, iso_names(axis),
                        profiles, tool_cam_mm)


# ----------------------------------------------------------------------------- D = 2: a planar (XY) stage
# The error motions of both axes of a planar (XY) stage, from every stop's full pose (SPEC 10, 14).
#
# Stage frame: X along the fitted X motion of the camera centre, Y its in-plane
# perpendicular towards +Y motion, Z = X x Y. Per stop (relative to the first
# usable stop) the rotation of the camera's attitude about X, Y, Z and the
# centre's displacement. A gantry's error is each axis' error as a function of
# its own position (:class:`~lps_gui.core.truth.stage_errors.PlanarErrorModel`), so
# every per-stop figure is fitted on the grid as f(x) + g(y) (least squares,
# g = 0 at the reference stop's y): the rotation about X as a function of x is
# EAX (roll of X), as a function of y EAY (pitch of Y), and so on; positioning
# EXX(x) and EYY(y) are the displacements along the axis minus the commanded,
# the straightness EYX, EZX (of x) and EXY, EZY (of y) the across-axis parts
# with their least-squares line taken out (its slope in the plane is the
# squareness, reported with the planar figures). Every figure is linear in the
# views' pose perturbations, so its sigma comes from the poses' full covariance
# (:meth:`PositionCovariance.weighted_variances`); a profile is resolved by
# :func:`lps_gui.core.metrology.resolution.profile_span`.

# (ISO name, along "X" or "Y", kind, component): kind "angle" (about stage X/Y/Z), "position" (along X/Y/Z)
PLANAR_MOTIONS = (
    ("EXX", 0, "position", 0), ("EYX", 0, "straightness", 1), ("EZX", 0, "straightness", 2),
    ("EAX", 0, "angle", 0), ("EBX", 0, "angle", 1), ("ECX", 0, "angle", 2),
    ("EYY", 1, "position", 1), ("EXY", 1, "straightness", 0), ("EZY", 1, "straightness", 2),
    ("EAY", 1, "angle", 0), ("EBY", 1, "angle", 1), ("ECY", 1, "angle", 2),
)
PLANAR_ANGLE_NAMES = ("EAX", "EBX", "ECX")  # per-stop columns of positions.csv: about the stage X, Y, Z (SPEC 14)


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
    weights: dict[str, np.ndarray]  # per ISO name (m, K): its values are weights @ the per-stop figure


def _plane_frame(C: np.ndarray, xy: np.ndarray, rows: np.ndarray) -> np.ndarray:
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


def planar_error_motions(sol: PoseSolution, targets_mm: np.ndarray, lens: LensTerm | None = None
                          ) -> PlanarErrorMotions:
    """The 12 error motions of an XY stage and the per-stop angles, with sigmas, from :func:`solve_poses`;
    ``lens`` as in :func:`error_motions`."""
    used = sol.used
    K = len(used)
    rows = np.flatnonzero(used)
    ref = int(rows[0])
    xy = np.asarray(targets_mm, float).reshape(K, 2)
    C, A, dC, dth = _grads(sol)
    S = _plane_frame(C, xy, rows)
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
    stop_var = [np.maximum(sol.covariance.weighted_variances(rel, g), 0.0) for g in grads["angle"]]
    if lens is not None:
        stop_var = [v + np.sum(lens.functional(g, rel, 1.0) ** 2, axis=1) for v, g in zip(stop_var, grads["angle"])]
    stop_sig = np.sqrt(np.stack(stop_var, axis=1)) * 1e6
    keys, W = _additive(xy, rows, ref)
    nx = len(keys[0])
    parts = {0: slice(0, nx), 1: slice(nx, None)}
    at_ref = (int(np.searchsorted(keys[0], round(float(xy[ref, 0]), 6))),
              int(np.searchsorted(keys[1], round(float(xy[ref, 1]), 6))))
    values, sigmas, centred, profiles, weights = {}, {}, {}, {}, {}
    for name, along, kind, comp in PLANAR_MOTIONS:
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
        weights[name] = w
        values[name] = w @ np.where(used, per_stop, 0.0)
        sigmas[name], centred[name], cov = _with_lens(sol, lens, grad, w, wc, unit,
                                                      _functional_sigmas(sol, grad, w, wc, unit))
        profiles[name] = profile_span(values[name], centred[name], keys[along], np.ones(len(keys[along]), bool),
                                      covariance=cov)
    stop_sig[~used] = np.nan
    angle[~used] = np.nan
    return PlanarErrorMotions(S, ref, angle, np.where(used[:, None], stop_sig, np.nan), {0: keys[0], 1: keys[1]},
                              values, sigmas, centred, profiles, {n: bool(p.resolved) for n, p in profiles.items()},
                              at_ref, weights)
