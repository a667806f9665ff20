"""The block arrowhead of models with targets (SPEC 13): normal equations, damped steps, covariance.

Every corner's residual depends on a few columns shared by all views (C of
them: the line model's R, l0 and tilt of N; none for free per-view poses),
on its own target's 6 (rotation, translation; target 0 is the world frame
and has none) and on its view's own P. So J^T J is an arrowhead: a dense
global block of G = C + 6 (T - 1) columns and a P x P block per view. The
views are eliminated by the Schur complement of :mod:`lps_gui.core.numerics.arrowhead` (b = P);
a step costs O(corners) plus a G x G solve, and the covariance stays factored:
Cov(v_i, v_k) = A_i^-1 [i = k] + W_i^T S^-1 W_k.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_parts
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.numerics.arrowhead import arrowhead_inverse, schur_step


@dataclass
class Linearization:
    """Residuals (M, 2) of the corners and their Jacobian blocks (None when only the cost was wanted)."""

    cost: float
    r: np.ndarray
    Jc: np.ndarray  # (M, 2, C) shared columns
    Jt: np.ndarray  # (M, 2, 6) the corner's own target (zero rows for target 0)
    Jv: np.ndarray  # (M, 2, P) the corner's own view


def project_residuals(P: np.ndarray, uv: np.ndarray, intrinsics: CameraIntrinsics, want_jacobian: bool = True):
    """Cost, residuals (M, 2) of camera-frame points P (M, 3) against corners uv, and d uv / d P (M, 2, 3) or None."""
    parts = project_parts(P[:, 0], P[:, 1], P[:, 2], intrinsics, want_jacobian)
    r = np.stack([parts.u, parts.v], axis=1) - uv
    cost = float(np.sum(r * r))
    if not want_jacobian:
        return cost, r, None
    return cost, r, np.stack([np.stack(parts.du, axis=1), np.stack(parts.dv, axis=1)], axis=1)


def normal_equations(lin: Linearization, tj: np.ndarray, view: np.ndarray, K: int, T: int, free_view: np.ndarray):
    """Arrowhead blocks: A_gg (G, G), A_gv (K, G, P), A_vv (K, P, P), b_g (G,), b_v (K, P).

    Every block is a sum over the (view, target) runs of corners (contiguous: corners are listed view
    by view, each view's targets end to end); the target-target part of A_gg is block diagonal.
    """
    Jc, Jt, r = lin.Jc, lin.Jt, lin.r
    C, P = Jc.shape[2], lin.Jv.shape[2]
    G = C + 6 * (T - 1)
    Jv = lin.Jv * free_view[view][:, None, None]
    key = view * T + tj
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    pv, pt = view[starts], tj[starts]
    # one pass: every corner's J^T J and J^T r over its C + 6 + P columns (two residual rows), summed per run
    J = np.concatenate([Jc, Jt, Jv], axis=2).reshape(2 * len(r), -1)  # two residual rows per corner
    rr = r.reshape(-1)
    ends = np.r_[starts[1:], len(r)]
    # a run is a few dozen corners: one small product per run beats outer products of every corner summed
    runs = np.stack([J[2 * a: 2 * b].T @ J[2 * a: 2 * b] for a, b in zip(starts.tolist(), ends.tolist())])
    rhs = np.stack([J[2 * a: 2 * b].T @ rr[2 * a: 2 * b] for a, b in zip(starts.tolist(), ends.tolist())])
    c, t6 = slice(0, C), slice(C, C + 6)
    v = slice(C + 6, C + 6 + P)
    tt, tv, vv = runs[:, t6, t6], runs[:, t6, v], runs[:, v, v]
    bt, bv = rhs[:, t6], rhs[:, v]
    cc, ct, cv = runs[:, c, c], runs[:, c, t6], runs[:, c, v]
    A_gg = np.zeros((G, G))
    b_g = np.zeros(G)
    A_gv = np.zeros((K, G, P))
    if C:
        A_gg[:C, :C] = cc.sum(axis=0)
        b_g[:C] = rhs[:, c].sum(axis=0)
        np.add.at(A_gv[:, :C], pv, cv)
    for j in range(1, T):
        on = pt == j
        if not on.any():
            continue
        sl = slice(C + 6 * (j - 1), C + 6 * j)
        if C:
            A_gg[:C, sl] = ct[on].sum(axis=0)
            A_gg[sl, :C] = A_gg[:C, sl].T
        A_gg[sl, sl] = tt[on].sum(axis=0)
        b_g[sl] = bt[on].sum(axis=0)
    A_vv = np.zeros((K, P, P))
    b_v = np.zeros((K, P))
    np.add.at(A_vv, pv, vv)
    np.add.at(b_v, pv, bv)
    tgt = pt > 0
    rows = C + 6 * (pt[tgt] - 1)[:, None] + np.arange(6)  # (runs, 6): the rows of each run's target
    A_gv[pv[tgt][:, None], rows] = tv[tgt]
    return A_gg, A_gv, A_vv, b_g, b_v


def damped_step(A_gg, A_gv, A_vv, b_g, b_v, lam: float, free_view: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Damped step (globals, views) by :func:`lps_gui.core.numerics.arrowhead.schur_step` (A_gv is B^T per view)."""
    return schur_step(A_gg, np.swapaxes(A_gv, 1, 2), A_vv, b_g, b_v, free_view, lam, screen=False)


def retract_targets(Q: np.ndarray, p: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Targets 1.. moved by their 6-vectors in ``d`` (rotation on the left, then translation)."""
    Q, p = Q.copy(), p.copy()
    for j in range(1, len(Q)):
        dj = d[6 * (j - 1): 6 * j]
        Q[j] = exp_so3(dj[0:3]) @ Q[j]
        p[j] = p[j] + dj[3:6]
    return Q, p


@dataclass
class Fit:
    state: Any
    lin: Linearization
    iterations: int
    converged: bool
    S_inv: np.ndarray
    W: np.ndarray
    Avv_inv: np.ndarray


def levenberg_marquardt(
    state: Any, linearize: Callable[..., Linearization], retract: Callable[[Any, np.ndarray, np.ndarray], Any],
    tj: np.ndarray, view: np.ndarray, K: int, T: int, free_view: np.ndarray, max_iterations: int = 50,
    tolerance: float = 1e-10, progress=None, label: str = "model",
) -> Fit:
    """Minimize the corners' squared residuals; the blocks at the end give the covariance (undamped)."""
    lam, converged, it = 1e-6, False, 0
    lin = linearize(state)
    for it in range(1, max_iterations + 1):
        blocks = normal_equations(lin, tj, view, K, T, free_view)
        while True:
            dg, dv = damped_step(*blocks, lam, free_view)
            trial = retract(state, dg, dv)
            cost_t = linearize(trial, False).cost  # the Jacobian only for a step that is taken
            if cost_t <= lin.cost or lam > 1e6:
                break
            lam *= 10.0
        gain = lin.cost - cost_t
        if cost_t <= lin.cost:
            state, lin = trial, linearize(trial)
            lam = max(lam / 10.0, 1e-9)
        if progress is not None:
            progress(it, max_iterations, f"{label}: iteration {it}, rms {np.sqrt(lin.cost / max(len(view), 1)):.3f} px")
        exact = lin.cost < 1e-20 * len(view)  # noise-free views (a planner's): nothing left to gain
        if gain <= tolerance * max(lin.cost, 1e-300) or lam > 1e6 or exact:
            # no step changes the cost by more than the tolerance, up or down: at the minimum to round-off
            converged = lam <= 1e6 or exact or abs(gain) <= tolerance * max(lin.cost, 1e-300)
            break
    A_gg, A_gv, A_vv, *_ = normal_equations(lin, tj, view, K, T, free_view)
    inv = arrowhead_inverse(A_gg, np.swapaxes(A_gv, 1, 2), A_vv, free_view, "the targets' poses",
                            "add stops where two targets are in view", screen=False)
    return Fit(state, lin, it, converged, inv.S_inv, np.swapaxes(inv.W, 1, 2), inv.D_inv)


def view_covariances(Avv_inv, W, S_inv, free_view, used):
    """Per-view covariances (K, P, P) in the solver's gauge and of v_i - mean_k v_k, unscaled.

    Cov(v_i, v_k) = A_i^-1 [i = k] + W_i^T S^-1 W_k for free views (a fixed view's block is zero).
    """
    Wf = W * free_view[:, None, None]
    Af = Avv_inv * free_view[:, None, None]
    cov = Af + np.einsum("kgd,gh,khe->kde", Wf, S_inv, Wf)
    n = max(int(used.sum()), 1)
    Wsum = Wf.sum(axis=0)
    cross = (Af + np.einsum("kgd,gh,he->kde", Wf, S_inv, Wsum)) / n  # Cov(v_i, mean v)
    var_mean = (Af.sum(axis=0) + Wsum.T @ S_inv @ Wsum) / n ** 2
    centred = cov - cross - np.swapaxes(cross, 1, 2) + var_mean
    return cov, centred


def view_rms(r: np.ndarray, view: np.ndarray, K: int) -> np.ndarray:
    """RMS reprojection error per view (px), NaN for views with no corner."""
    sq = np.bincount(view, weights=np.sum(r * r, axis=1), minlength=K)
    cnt = np.bincount(view, minlength=K)
    return np.where(cnt > 0, np.sqrt(sq / np.maximum(cnt, 1)), np.nan)


@dataclass
class PositionCovariance:
    """The views' full covariance, kept factored: Cov(v_i, v_k) = A_i [i = k] + W_i^T S^-1 W_k, scaled.

    ``turn`` (P, P) maps the solver's view coordinates to the reported ones (v_reported = v turn).
    """

    A_inv: np.ndarray  # (K, P, P), zero for fixed views
    W: np.ndarray  # (K, G, P)
    S_inv: np.ndarray  # (G, G)
    sigma2: float
    turn: np.ndarray

    def variance(self, g: np.ndarray) -> float:
        """Variance of sum_i g_i . v_i for weights g (K, P) on the reported coordinates."""
        gs = g @ self.turn.T
        w = np.einsum("kgd,kd->g", self.W, gs)
        return float(self.sigma2 * (np.einsum("kd,kde,ke->", gs, self.A_inv, gs) + w @ self.S_inv @ w))

    def variances(self, g: np.ndarray) -> np.ndarray:
        """Variances of Q linear functionals sum_k g[q, k] . v_k, weights g (Q, K, P) on the reported coordinates."""
        gs = g @ self.turn.T
        wg = np.einsum("kgp,qkp->qg", self.W, gs)
        own = np.einsum("qkp,kpr,qkr->q", gs, self.A_inv, gs)
        return self.sigma2 * (own + np.einsum("qg,gh,qh->q", wg, self.S_inv, wg))

    def covariance(self, g: np.ndarray) -> np.ndarray:
        """Covariance (Q, Q) of Q linear functionals, weights g (Q, K, P) on the reported coordinates."""
        gs = g @ self.turn.T
        wg = np.einsum("kgp,qkp->qg", self.W, gs)
        return self.sigma2 * (np.einsum("qkp,kpr,nkr->qn", gs, self.A_inv, gs) + wg @ self.S_inv @ wg.T)

    def weighted_variances(self, w: np.ndarray, g: np.ndarray) -> np.ndarray:
        """:meth:`variances` of functionals sum_k w[q, k] g[k] . v_k: weights w (Q, K) times one g (K, P).

        The same numbers in O(Q K) memory instead of O(Q K P) (error motions over K = 1600 stops).
        """
        gs = g @ self.turn.T
        own = np.einsum("kp,kpr,kr->k", gs, self.A_inv, gs)
        wg = w @ np.einsum("kgp,kp->kg", self.W, gs)
        return self.sigma2 * ((w * w) @ own + np.einsum("qg,gh,qh->q", wg, self.S_inv, wg))

    def weighted_covariance(self, w: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The (Q, Q) covariance whose diagonal is :meth:`weighted_variances`: correlated through the targets."""
        gs = g @ self.turn.T
        own = np.einsum("kp,kpr,kr->k", gs, self.A_inv, gs)
        wg = w @ np.einsum("kgp,kp->kg", self.W, gs)
        return self.sigma2 * ((w * own) @ w.T + wg @ self.S_inv @ wg.T)

    @property
    def shares_targets(self) -> bool:
        """True when the views' errors are correlated through estimated targets (not one known board)."""
        return self.S_inv.size > 0 and bool(np.any(self.W))

    def cross(self, i: int, k: int) -> np.ndarray:
        """Cov(v_i, v_k) (P, P) in the solver's coordinates, scaled."""
        c = self.W[i].T @ self.S_inv @ self.W[k]
        if i == k:
            c = c + self.A_inv[i]
        return self.sigma2 * c
