"""The Cramer-Rao bound of the row / constellation model (SPEC 13), from central differences of the projection.

Shared by the model's tests and the pipeline's: the bound is built at the simulator's truth (target poses and
positions) with the solver's own parametrization, independent of the solver's covariance.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.models.target_model import N_COMMON, _linearize, _retract, initial_solution


def crb_centred(obs, layout, s_true, D: int, noise_px: float, intrinsics) -> np.ndarray:
    """Cramer-Rao bound of every centred position, from central differences of the simulator's projection."""
    K, T = len(obs.names), len(obs.targets)
    seen = np.isfinite(obs.corners_px[..., 0])
    state = initial_solution(obs, intrinsics)
    # linearize at the truth: the true layout and positions with the solver's parametrization (R, l0, N fitted)
    state["Q"], state["p"] = layout.Q.copy(), layout.p.copy()
    state["s"] = s_true.reshape(K, D) - s_true.reshape(K, D)[state["ref"]]
    view, corner = np.nonzero(seen)
    X, tj, uv = obs.own_points[corner], obs.which[corner], obs.corners_px[view, corner]
    G = N_COMMON + 6 * (T - 1)
    cols = []
    h = 1e-6

    def residual(dg, dv):
        return _linearize(_retract(state, dg, dv, D, T), X, tj, view, uv, intrinsics, D, False).r.ravel()

    zero_v = np.zeros((K, D))
    for g in range(G):
        e = np.zeros(G)
        e[g] = h
        cols.append((residual(e, zero_v) - residual(-e, zero_v)) / (2 * h))
    for i in range(K):
        for d in range(D):
            if i == state["ref"]:
                continue
            dv = zero_v.copy()
            dv[i, d] = h
            cols.append((residual(np.zeros(G), dv) - residual(np.zeros(G), -dv)) / (2 * h))
    J = np.stack(cols, axis=1)
    cov = noise_px ** 2 * np.linalg.inv(J.T @ J)
    free = [(i, d) for i in range(K) for d in range(D) if i != state["ref"]]
    C = np.zeros((K * D, K * D))
    idx = [i * D + d for i, d in free]
    C[np.ix_(idx, idx)] = cov[G:, G:]
    Cm = C.reshape(K, D, K, D)
    out = np.zeros((K, D))
    for d in range(D):
        c = Cm[:, d, :, d]
        centring = np.eye(K) - 1.0 / K
        out[:, d] = np.sqrt(np.diag(centring @ c @ centring))
    return out
