"""The analytic normal equations of every stage model against central finite differences, as one table.

Rows: the model of D axes (line: core/models/joint_lm; planar: core/models/planar_model; SPEC 13's target rows join
here). Columns: which parameter groups are differentiated (mrcal's test-gradients varies its problem
selections the same way): ``poses`` (the shared rotation and line or plane, and every view's position),
``intrinsics`` (the 9 intrinsics beside them) and ``warp`` (both, on a bowed board whose points leave the
plane, so every z term of the Jacobian counts). Each cell also shows that the check can fail: one
chain-rule term scaled by 1.01 in the model's projection is caught.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np
import pytest

from lps_gui.core.models.joint_lm import N_POSE_PARAMS, LpsState, apply_step, linearize, residuals
from lps_gui.core.models.planar_model import (
    N_PLANAR_SHARED,
    PlanarState,
    apply_planar_step,
    linearize_planar,
    planar_residuals,
)
from lps_gui.core.truth.simulate import nominal_planar_state, simulate_views, small_planar_spec, small_spec
from tests.core.finite_differences import central_jacobian, normalized_difference

TOL = 1e-5  # a Jacobian column scaled by 1.01 moves the normal matrix by ~1e-2 in these units
WARP_MM = (1.5, -1.0)
H_INTRINSICS = np.r_[np.full(4, 1e-3), np.full(5, 1e-6)]  # fx, fy, cx, cy in px; distortion


@dataclass
class Case:
    """One model at a point near (not at) its solution: noisy corners, a few missing, residuals not zero."""

    model: str
    state: object
    X: np.ndarray
    corners: np.ndarray
    mask: np.ndarray
    module: str  # where the model's projection is looked up (the negative control patches it there)


def _noisy(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    corners = corners.copy()
    corners[2, :5] = np.nan  # a few corners not found
    return corners, np.all(np.isfinite(corners), axis=-1)


def line_case(warp: bool) -> Case:
    spec = small_spec(seed=4, views=8, noise_px=0.3)
    views = simulate_views(spec)
    rig = spec.rig
    rng = np.random.default_rng(1)
    s = np.asarray(views.truth["positions_mm"]) + rng.normal(0, 0.01, len(views.stops))
    state = LpsState(rig.R_cam_board, views.t_cam_board[0] + 0.05, -rig.R_cam_board @ rig.u_board, s, rig.intrinsics)
    board = replace(rig.board, warp_mm=WARP_MM) if warp else rig.board
    return Case("line", state, board.object_points(), *_noisy(views.corners_px), "lps_gui.core.numerics.pose_normals")


def planar_case(warp: bool) -> Case:
    spec = small_planar_spec(seed=3, noise_px=0.3)
    views = simulate_views(spec)
    rng = np.random.default_rng(2)
    state = nominal_planar_state(spec.rig, views.board_plane_mm + rng.normal(0, 0.01, views.board_plane_mm.shape))
    state.l0 = state.l0 + 0.05
    board = replace(spec.rig.board, warp_mm=WARP_MM) if warp else spec.rig.board
    return Case("planar", state, board.object_points(), *_noisy(views.corners_px), "lps_gui.core.models.planar_model")


def line_analytic(case: Case, with_intrinsics: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H over (theta [+ intrinsics], s), the gradient and the residuals, from joint_lm.linearize."""
    eq, r = linearize(case.state, case.X, case.corners, case.mask, with_intrinsics=with_intrinsics)
    H = np.block([[eq.A, eq.B.T], [eq.B, np.diag(eq.D)]])
    return H, np.r_[eq.g_theta, eq.g_s], r


def line_numeric(case: Case, with_intrinsics: bool) -> np.ndarray:
    """d r / d (theta [+ intrinsics], s) through the solver's own update rule (apply_step)."""
    st = case.state
    basis = linearize(st, case.X, case.corners, case.mask)[0].basis
    p = N_POSE_PARAMS + (9 if with_intrinsics else 0)
    K = st.s.size

    def r_of(step):
        return residuals(apply_step(st, step[:p], step[p:], basis), case.X, case.corners, case.mask).reshape(-1)

    h = np.r_[np.full(3, 1e-6), np.full(3, 1e-4), np.full(2, 1e-6), H_INTRINSICS[: p - N_POSE_PARAMS], np.full(K, 1e-4)]
    return central_jacobian(r_of, p + K, h)


def planar_analytic(case: Case, with_intrinsics: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H over (theta [+ intrinsics], xy) from linearize_planar, its 2x2 blocks laid out densely."""
    eq, r = linearize_planar(case.state, case.X, case.corners, case.mask, with_intrinsics=with_intrinsics)
    K, p = eq.D.shape[0], eq.A.shape[0]
    H = np.zeros((p + 2 * K, p + 2 * K))
    H[:p, :p] = eq.A
    B = eq.B.reshape(2 * K, p)
    H[p:, :p], H[:p, p:] = B, B.T
    for k in range(K):
        H[p + 2 * k:p + 2 * k + 2, p + 2 * k:p + 2 * k + 2] = eq.D[k]
    return H, np.r_[eq.g_theta, eq.g_s.reshape(-1)], r


def planar_numeric(case: Case, with_intrinsics: bool) -> np.ndarray:
    """d r / d (theta [+ intrinsics], xy) through the solver's own update rule (apply_planar_step)."""
    st: PlanarState = case.state
    K = st.xy.shape[0]
    p = N_PLANAR_SHARED + (9 if with_intrinsics else 0)

    def r_of(step):
        moved = apply_planar_step(st, step[:p], step[p:].reshape(K, 2))
        return planar_residuals(moved, case.X, case.corners, case.mask).reshape(-1)

    h = np.r_[np.full(3, 1e-6), np.full(3, 1e-4), np.full(2, 1e-6), H_INTRINSICS[: p - N_PLANAR_SHARED],
              np.full(2 * K, 1e-4)]
    return central_jacobian(r_of, p + 2 * K, h)


MODELS: dict[str, tuple[Callable, Callable, Callable]] = {
    "line": (line_case, line_analytic, line_numeric),
    "planar": (planar_case, planar_analytic, planar_numeric),
}
SELECTIONS = {"poses": (False, False), "intrinsics": (True, False), "warp": (True, True)}  # (intrinsics, bowed)


@pytest.fixture(scope="module", params=[(m, s) for m in MODELS for s in SELECTIONS], ids=lambda ms: f"{ms[0]}-{ms[1]}")
def cell(request):
    model, selection = request.param
    with_intrinsics, warp = SELECTIONS[selection]
    make, analytic, numeric = MODELS[model]
    case = make(warp)
    J = numeric(case, with_intrinsics)
    return case, with_intrinsics, analytic, J


def _difference(H: np.ndarray, J: np.ndarray) -> float:
    return normalized_difference(H, J.T @ J)


def test_normal_equations_match_central_differences(cell):
    case, with_intrinsics, analytic, J = cell
    H, g, r = analytic(case, with_intrinsics)
    assert H.shape == (J.shape[1], J.shape[1])
    assert _difference(H, J) < TOL
    g_num = J.T @ r.reshape(-1)
    scale = np.sqrt(np.diag(J.T @ J)) * np.linalg.norm(r)
    assert np.max(np.abs(g - g_num) / scale) < TOL


def test_a_wrong_chain_rule_term_fails_the_check(cell, monkeypatch):
    """Scale d u / d z by 1.01 in the model's projection (one term of every column that moves z): caught."""
    import importlib

    case, with_intrinsics, analytic, J = cell
    module = importlib.import_module(case.module)
    real = module.project_parts

    def skewed(x, y, z, intrinsics, want_jacobian=False):
        parts = real(x, y, z, intrinsics, want_jacobian)
        if want_jacobian:
            parts = parts._replace(du=(parts.du[0], parts.du[1], 1.01 * parts.du[2]))
        return parts

    monkeypatch.setattr(module, "project_parts", skewed)
    H, _, _ = analytic(case, with_intrinsics)
    monkeypatch.setattr(module, "project_parts", real)
    assert _difference(H, J) > 100 * TOL
