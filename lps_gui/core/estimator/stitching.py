"""Stitching segments of one moved board (SPEC 13): the whole travel without a fixed row of targets.

A user with one board measures the travel in segments: capture a segment, move
the board along, capture the next one starting a few stops before the last one
ended. Each segment's board is a target of its own (its pose unknown, as a
row's); no view sees two of them, so the overlap ties them instead: at a stop
commanded in both segments the stage returns to the same position up to its
repeatability, and the two views of it are one camera position that sees both
boards. Merging each such pair into one view gives the row model its ties
(:func:`lps_gui.core.models.target_model.solve_targets` chains and solves it as any
row).

What the merge assumes is exact holds only to the stage's repeatability
sigma_r: the offset of segment b + 1 against segment b is the mean over its n_b
tied stops of the difference of two visits, so it carries 2 sigma_r^2 / n_b of
variance, and a position in segment m carries the sum over the boundaries
between it and the reference segment. That enters each position's sigma and
the budget ("stage repeatability at the segment ties"). No I/O, no Qt.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.metrology.uncertainty_budget import BudgetRow
from lps_gui.core.estimator.board_plane_positions import row_with_board_plane_positions
from lps_gui.core.models.target_model import (
    TargetObservations,
    TargetSolution,
    row_parameter_count,
    solve_targets,
)
from lps_gui.core.numerics.target_arrowhead import PositionCovariance
from lps_gui.errors import DegenerateGeometryError, InputError

SAME_STOP_MM = 1e-6  # two commanded positions closer than this are one stop
TIE_SOURCE = "stage repeatability at the segment ties"


@dataclass
class StitchedSolution:
    """The row solution of the merged views, and each original view's position with the stitch term."""

    solution: TargetSolution  # of the merged views
    view_of: np.ndarray  # (K,) merged view of each original view
    ties: list[np.ndarray]  # per boundary b (segment b to b + 1): (n_b, 2) original view pairs
    s: np.ndarray  # (K, D) mm, relative to the reference view
    sigma_noise: np.ndarray  # (K, D) mm: corner noise (the row model's sigma)
    sigma_stitch: np.ndarray  # (K,) mm: the repeatability of the ties between the view's and the reference segment
    sigma_total: np.ndarray  # (K, D) mm
    crossing: np.ndarray  # (K, B): +1 / -1 where boundary b lies between the view's and the reference segment
    boundary_variance_mm2: np.ndarray  # (B,)


def segment_ties(targets_mm: np.ndarray, segment: np.ndarray) -> list[np.ndarray]:
    """For each boundary between segment b and b + 1, the pairs (earlier view, later view) of a stop commanded in both.

    Each view is tied at most once: the k-th visit of a stop in segment b + 1 pairs with the k-th in segment b.
    A boundary without a common stop is a one-line error (the segments could not be tied).
    """
    x = np.asarray(targets_mm, float).reshape(len(segment), -1)
    segment = np.asarray(segment, int)
    n_seg = int(segment.max()) + 1
    if sorted(set(segment.tolist())) != list(range(n_seg)):
        raise InputError(f"segments must be numbered 0 .. {n_seg - 1} without gaps; got {sorted(set(segment.tolist()))}")
    out = []
    for b in range(n_seg - 1):
        early, late = np.flatnonzero(segment == b), np.flatnonzero(segment == b + 1)
        used: set[int] = set()
        pairs = []
        for j in late:
            same = [i for i in early if i not in used and np.all(np.abs(x[i] - x[j]) < SAME_STOP_MM)]
            if same:
                used.add(same[0])
                pairs.append((same[0], j))
        if not pairs:
            raise InputError(f"segment {b + 1} has no stop in common with segment {b}: after moving the board, repeat "
                             f"the last stops of segment {b} (3 or more) so the two segments are tied")
        out.append(np.array(pairs, int))
    return out


def merged_observations(obs: TargetObservations, ties: list[np.ndarray]) -> tuple[TargetObservations, np.ndarray]:
    """Each tied pair as one view seeing both boards; ``view_of`` (K,) maps every view to its merged view."""
    K = len(obs.names)
    into = np.arange(K)
    for pairs in ties:
        into[pairs[:, 1]] = into[pairs[:, 0]]  # a later visit joins its earlier one (which stays where it is)
    keep = np.flatnonzero(into == np.arange(K))
    view_of = np.searchsorted(keep, into)
    corners = obs.corners_px[keep].copy()
    names = [obs.names[i] for i in keep]
    for j in np.flatnonzero(into != np.arange(K)):
        k = view_of[j]
        mine = np.isfinite(obs.corners_px[j, :, 0])
        corners[k, mine] = obs.corners_px[j, mine]  # the boards differ, so their corners never overlap
        names[k] = f"{names[k]}+{obs.names[j]}"
    return TargetObservations(obs.targets, corners, obs.targets_mm[keep], names), view_of


def row_dof(obs: TargetObservations, sol: TargetSolution) -> int:
    """Degrees of freedom of the row model's fit of ``obs`` (one axis; the estimate's count)."""
    n_obs = 2 * int((np.isfinite(obs.corners_px[..., 0]) & sol.used[:, None]).sum())
    return n_obs - row_parameter_count(len(obs.targets), sol.bows_mm is not None, int(sol.used.sum()))


def stitch_variance_mm2(ties: list[np.ndarray], repeatability_mm: float) -> np.ndarray:
    """Variance each boundary's offset carries (n_b ties of two visits each): 2 sigma_r^2 / n_b, shape (B,)."""
    return np.array([2.0 * repeatability_mm ** 2 / len(p) for p in ties])


def solve_stitched(obs: TargetObservations, segment: np.ndarray, intrinsics: CameraIntrinsics,
                   repeatability_mm: float, noise_px: float | None = None, **solver) -> StitchedSolution:
    """Positions of every view of a segmented capture against one moved board (one target per segment)."""
    segment = np.asarray(segment, int)
    if len(obs.targets) != int(segment.max()) + 1:
        raise InputError(f"a stitched capture has one target per segment: {len(obs.targets)} targets for "
                         f"{int(segment.max()) + 1} segments")
    if not repeatability_mm >= 0:
        raise InputError(f"the stage repeatability must be 0 or more, got {repeatability_mm} mm")
    ties = segment_ties(obs.targets_mm, segment)
    merged, view_of = merged_observations(obs, ties)
    try:
        sol = solve_targets(merged, intrinsics, noise_px=noise_px, **solver)
    except DegenerateGeometryError as exc:
        raise DegenerateGeometryError(f"{exc} (a stitched capture: the tied stops must see both boards)") from None
    if sol.s.shape[1] == 1 and noise_px is None:  # a carriage the row model cannot follow: every stop's own pose
        sol = row_with_board_plane_positions(merged, sol, intrinsics, row_dof(merged, sol))
    var_b = stitch_variance_mm2(ties, repeatability_mm)
    ref_segment = segment[np.flatnonzero(view_of == sol.reference)[0]]
    b = np.arange(len(ties))
    crossing = (((b >= ref_segment) & (b < segment[:, None])).astype(float)
                - ((b < ref_segment) & (b >= segment[:, None])).astype(float))
    sigma_stitch = np.sqrt(crossing ** 2 @ var_b)
    s, noise = sol.s[view_of], sol.sigma_s[view_of]
    total = np.sqrt(noise ** 2 + sigma_stitch[:, None] ** 2)
    return StitchedSolution(sol, view_of, ties, s, noise, sigma_stitch, total, crossing, var_b)


@dataclass
class StitchedCovariance:
    """The positions' covariance of every original view: the merged views' (tied visits share one position)
    plus the boundary offsets' (independent, variance ``var_b``, entering a view with ``crossing``).

    Answers as :class:`PositionCovariance` does (reported coordinates, one axis); ``S_inv`` and ``sigma2``
    are the merged solution's (its shared and target parameters).
    """

    merged: PositionCovariance
    view_of: np.ndarray  # (K,)
    crossing: np.ndarray  # (K, B)
    var_b: np.ndarray  # (B,) mm^2

    @property
    def S_inv(self) -> np.ndarray:
        return self.merged.S_inv

    @property
    def sigma2(self) -> float:
        return self.merged.sigma2

    @property
    def turn(self) -> np.ndarray:
        return self.merged.turn

    def _merge(self, g: np.ndarray) -> np.ndarray:
        """Weights (..., K, P) on the original views as weights on the merged views (a tie's two visits add)."""
        by_view = np.moveaxis(np.asarray(g, float), -2, 0)
        out = np.zeros((int(self.view_of.max()) + 1,) + by_view.shape[1:])  # every merged view is some view's
        np.add.at(out, self.view_of, by_view)
        return np.moveaxis(out, 0, -2)

    def variance(self, g: np.ndarray) -> float:
        """Variance of sum_i g_i . v_i, weights g (K, P)."""
        offsets = self.crossing.T @ g[:, 0]
        return self.merged.variance(self._merge(g)) + float(offsets ** 2 @ self.var_b)

    def variances(self, g: np.ndarray) -> np.ndarray:
        """Variances of Q functionals, weights g (Q, K, P)."""
        offsets = g[..., 0] @ self.crossing  # (Q, B)
        return self.merged.variances(self._merge(g)) + offsets ** 2 @ self.var_b

    def covariance(self, g: np.ndarray) -> np.ndarray:
        """Covariance (Q, Q) of Q functionals, weights g (Q, K, P)."""
        offsets = g[..., 0] @ self.crossing  # (Q, B)
        return self.merged.covariance(self._merge(g)) + (offsets * self.var_b) @ offsets.T

    def cross(self, i: int, k: int) -> np.ndarray:
        """Cov(v_i, v_k) (P, P) of two original views."""
        shared = float(self.crossing[i] * self.crossing[k] @ self.var_b)
        return self.merged.cross(int(self.view_of[i]), int(self.view_of[k])) + shared


def stitched_target_solution(obs: TargetObservations, segment: np.ndarray, intrinsics: CameraIntrinsics,
                             repeatability_mm: float, progress=None) -> tuple[TargetSolution, StitchedSolution]:
    """The row model's answer for every original view of a stitched capture (what the one estimator takes)."""
    # each placement's bow free, as a row's targets': a bow held flat reads as scale along the chain (0.3 mm:
    # -120 ppm), and the rendered realism-on sessions' scale was covered 70 % of the time (docs/validation.md)
    st = solve_stitched(obs, segment, intrinsics, repeatability_mm, progress=progress, bows=True)
    m, v = st.solution, st.view_of
    ref = int(np.flatnonzero(v == m.reference)[0])
    centred = np.sqrt(m.sigma_centred[v] ** 2 + st.sigma_stitch[:, None] ** 2)
    ties = m.ties  # the merged views' (T, T): the tie views see both boards
    sol = replace(m, s=st.s, sigma_s=st.sigma_total, sigma_centred=centred, rms_px=m.rms_px[v], used=m.used[v],
                  reference=ref, ties=ties, covariance=StitchedCovariance(m.covariance, v, st.crossing,
                                                                          st.boundary_variance_mm2),
                  intrinsics_gradient=None if m.intrinsics_gradient is None else m.intrinsics_gradient[v])
    return sol, st


def stitch_budget_row(ties: list[np.ndarray], repeatability_um: float | None) -> BudgetRow:
    """The ties' term of the budget for a displacement over the whole travel (every boundary crossed)."""
    c = float(np.sqrt(np.sum([2.0 / max(len(p), 1) for p in ties])))  # um of the travel per um of repeatability
    where = f"{len(ties)} boundaries, {', '.join(str(len(p)) for p in ties)} tied stops"
    if repeatability_um is None:
        return BudgetRow(TIE_SOURCE, "B", None, "\u00b5m", c, None,
                         f"stage repeatability not stated; {where}; not in U")
    return BudgetRow(TIE_SOURCE, "B", float(repeatability_um), "\u00b5m", c, c * float(repeatability_um),
                     f"the board was moved between segments; {where}: sqrt(sum 2 / n_b) per \u00b5m of repeatability")
