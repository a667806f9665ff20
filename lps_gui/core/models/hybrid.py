"""The paper's hybrid algorithm (SPEC 4.3), step by step.

1. per-view PnP -> R_i, t_i (Eq. 3);
2. initial R = chordal mean of R_i, line (l0, n) by PCA of the t_i, n oriented
   along increasing target, positions at their nominal values (Eq. 5);
3. LM on Eq. 4 over R, l0, n with the positions held at their current values;
4. for every view independently, a 1-D grid search of s_i minimizing that
   view's reprojection error (Eq. 6);
5. repeat 3-4 until the reprojection error is below T or stops improving.

Step 4's grid is searched coarse-to-fine: an exhaustive grid of ``grid_points``
over +-``window_mm``, then an exhaustive grid over the best cell +- one
spacing, until the spacing reaches ``resolution_mm``. Each level is a plain
grid search; the levels only avoid evaluating 10^4 points per view.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_parts
from lps_gui.core.geometry.rotation import chordal_mean
from lps_gui.core.models.joint_lm import LmOptions, LmResult, LpsState, linearize, solve_joint
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import DegenerateGeometryError, InputError

MAX_WINDOW_MM = 1000.0  # +-1 m around each position: more than any stage's error
MAX_GRID_SPAN = 1e9  # window / resolution: the coarse-to-fine levels stay a few dozen


@dataclass
class HybridOptions:
    """Settings of the paper's algorithm."""

    window_mm: float = 0.5  # grid half-width around the current s_i
    resolution_mm: float = 1e-4  # final grid spacing (0.1 um)
    grid_points: int = 21  # points per grid level
    threshold_rms_px: float | None = None  # T, as an RMS reprojection error; None: run until no improvement
    max_rounds: int = 30
    relative_improvement: float = 1e-9
    adaptive_window: bool = True  # later rounds search +-4x the previous round's largest move (>= 10 steps)

    def __post_init__(self) -> None:
        """A zero or NaN window echoes the targets as measurements; a huge one (or a tiny spacing) runs for ever."""
        w, r, t = self.window_mm, self.resolution_mm, self.threshold_rms_px
        if not (np.isfinite(w) and 0 < w <= MAX_WINDOW_MM):
            raise InputError(f"hybrid: grid-window-mm {w} must be over 0 and at most {MAX_WINDOW_MM:g} mm (default 0.5)")
        if not (np.isfinite(r) and 0 < r <= w):
            raise InputError(f"hybrid: grid-resolution-mm {r} must be over 0 and at most the window {w:g} mm "
                             "(default 0.0001)")
        if w / r > MAX_GRID_SPAN:
            raise InputError(f"hybrid: the grid of +-{w:g} mm at {r:g} mm spacing has {2 * w / r:.3g} points (at most "
                             f"{2 * MAX_GRID_SPAN:g}); widen --grid-resolution-mm or narrow --grid-window-mm")
        if not (isinstance(self.grid_points, int) and 3 <= self.grid_points <= 10_000):
            raise InputError(f"hybrid: grid_points {self.grid_points} must be a whole number from 3 to 10000")
        if t is not None and not (np.isfinite(t) and t > 0):
            raise InputError(f"hybrid: threshold-px {t} must be a positive number (or none: until no improvement)")


@dataclass
class HybridResult:
    state: LpsState
    lm: LmResult  # the last step-3 solve
    rounds: int
    rms_history_px: list[float] = field(default_factory=list)
    converged: bool = False


def initial_line(
    R_views: np.ndarray, t_views: np.ndarray, target_mm: np.ndarray, intrinsics: CameraIntrinsics
) -> LpsState:
    """Eq. 5 initialization from per-view poses of the usable views.

    R: chordal mean; n: first principal direction of the t_i, oriented so
    that t moves along +n as the target grows; s_i: nominal (target - first
    target); l0: least-squares offset of the line given those positions.
    """
    R = chordal_mean(R_views)
    t_mean = t_views.mean(axis=0)
    _, sing, Vt = np.linalg.svd(t_views - t_mean, full_matrices=False)
    if sing[0] <= 1e-9 * max(1.0, np.abs(t_mean).max()):
        raise DegenerateGeometryError("all views show the board from one place; the line direction is undetermined")
    n = Vt[0]
    dt = target_mm - target_mm.mean()
    if np.dot((t_views - t_mean) @ n, dt) < 0:
        n = -n
    s = target_mm - target_mm[0]
    l0 = np.mean(t_views - s[:, None] * n[None, :], axis=0)
    return LpsState(R, l0, n, s.astype(float), intrinsics)


def view_costs(state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Sum of squared reprojection errors of each view, shape (K,) px^2."""
    return grid_costs(state, X, corners, mask, state.s[:, None])[:, 0]


def grid_costs(
    state: LpsState, X: np.ndarray, corners: np.ndarray, mask: np.ndarray, s_candidates: np.ndarray, chunk: int = 32
) -> np.ndarray:
    """Eq. 6 cost of every candidate position of every view, shape (K, G) px^2.

    ``s_candidates`` has shape (K, G); the shared parameters stay fixed.
    """
    base = X @ state.R.T + state.l0  # shape (N, 3)
    mu, mv = np.nan_to_num(corners[..., 0]), np.nan_to_num(corners[..., 1])
    K, G = s_candidates.shape
    out = np.empty((K, G))
    for start in range(0, K, chunk):
        sl = slice(start, min(K, start + chunk))
        s = s_candidates[sl, :, None]  # shape (k, G, 1)
        x = base[None, None, :, 0] + s * state.n[0]  # shape (k, G, N)
        y = base[None, None, :, 1] + s * state.n[1]
        z = base[None, None, :, 2] + s * state.n[2]
        parts = project_parts(x, y, z, state.intrinsics)
        e2 = (parts.u - mu[sl, None, :]) ** 2 + (parts.v - mv[sl, None, :]) ** 2
        out[sl] = np.einsum("kgn,kn->kg", e2, mask[sl].astype(float))
    return out


def grid_search_positions(
    state: LpsState,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    views: np.ndarray,
    window_mm: float,
    resolution_mm: float,
    grid_points: int = 21,
) -> np.ndarray:
    """Step 4: per-view grid search of s_i around the current positions; returns new s (K,)."""
    if grid_points < 3:
        raise ValueError("grid_points must be at least 3")
    s = state.s.copy()
    idx = np.flatnonzero(views)
    half = float(window_mm)
    while True:
        offsets = np.linspace(-half, half, grid_points)
        spacing = offsets[1] - offsets[0]
        cand = s[idx, None] + offsets[None, :]
        costs = grid_costs(state, X, corners[idx], mask[idx], cand)
        s[idx] = cand[np.arange(idx.size), np.argmin(costs, axis=1)]
        if spacing <= resolution_mm:
            return s
        half = spacing


def solve_hybrid(
    state: LpsState,
    X: np.ndarray,
    corners: np.ndarray,
    mask: np.ndarray,
    views: np.ndarray,
    options: HybridOptions | None = None,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> HybridResult:
    """Steps 3-5 of the paper from an initial state (steps 1-2 give it)."""
    opt = options or HybridOptions()
    lm_opt = LmOptions(fix_positions=True)
    free = np.zeros(len(state.s), dtype=bool)
    history: list[float] = []
    n_obs = max(1, int(2 * mask.sum()))
    lm = None
    converged = False
    rounds = 0
    window = opt.window_mm
    for rounds in range(1, opt.max_rounds + 1):
        if cancel is not None:
            cancel.check("hybrid estimation")
        lm = solve_joint(state, X, corners, mask, free, lm_opt, cancel)  # step 3
        state = lm.state
        before = state.s.copy()
        state.s = grid_search_positions(  # step 4
            state, X, corners, mask, views, window, opt.resolution_mm, opt.grid_points
        )
        if opt.adaptive_window:
            moved = float(np.max(np.abs(state.s - before)[views], initial=0.0))
            window = float(np.clip(4.0 * moved, 10.0 * opt.resolution_mm, opt.window_mm))
        rms = float(np.sqrt(np.sum(view_costs(state, X, corners, mask)[views]) / n_obs))
        progress(rounds, opt.max_rounds, f"hybrid round {rounds}: RMS {rms:.4f} px")
        improving = not history or rms < history[-1] * (1.0 - opt.relative_improvement)
        history.append(rms)
        if opt.threshold_rms_px is not None and rms < opt.threshold_rms_px:
            converged = True
            break
        if not improving:
            converged = True
            break
    assert lm is not None
    eq, _ = linearize(state, X, corners, mask)
    lm = LmResult(state, eq.weights, eq, lm.iterations, converged, lm.cost_history)
    return HybridResult(state, lm, rounds, history, converged)
