"""The estimators' input: corners of K views of one board, with capture metadata."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.targets import Target, target_offsets
from lps_gui.errors import DegenerateGeometryError, InputError

MIN_CORNERS_PER_VIEW = 6
UNSPANNED = {  # targets that do not span the stage's D axes, by D
    1: "all views are at one target position; the line direction is undetermined, capture along the axis",
    2: "the usable targets lie on one line; a planar session needs targets spread over both axes "
       "(or estimate it as 1-D)",
}


class CornerViews:
    """What every estimator's input knows of its corners (``corners_px`` shape (K, N, 2), NaN where missing)."""

    corners_px: np.ndarray

    @property
    def K(self) -> int:
        return self.corners_px.shape[0]

    @property
    def N(self) -> int:
        return self.corners_px.shape[1]

    def mask(self) -> np.ndarray:
        """Which corners were seen, shape (K, N) bool."""
        c = self.corners_px
        return np.isfinite(c[..., 0]) & np.isfinite(c[..., 1])  # a reduction over the axis of length 2 costs 4x more

    def usable_views(self) -> np.ndarray:
        """Views with enough corners for a pose, shape (K,) bool."""
        return self.mask().sum(axis=1) >= MIN_CORNERS_PER_VIEW


@dataclass
class Observations(CornerViews):
    """Corners of K views (NaN where missing) and what the stage was told to do, on D = 1 or 2 axes.

    ``target_mm`` is shape (K,) for one axis and (K, 2) for an XY stage
    (SPEC 10); :attr:`D` says which, :attr:`targets` is always (K, D).
    ``approach`` is each axis' approach side (+1/-1, shape (K, D)); for one
    axis it is the pass direction.

    A session with targets (SPEC 13: a row or constellation) names them in
    ``mounted``: the corners of every target laid end to end (target j's at
    ``target_offsets(mounted)[j]`` ...), ``corner_target`` (N,) the target of
    each corner, and ``board`` the first target's board (the world frame).
    """

    board: Board
    intrinsics: CameraIntrinsics
    corners_px: np.ndarray  # shape (K, N, 2)
    target_mm: np.ndarray  # shape (K,) for one axis, (K, 2) for two
    direction: np.ndarray  # shape (K,): +1 forward, -1 backward
    run: np.ndarray  # shape (K,) int
    index: np.ndarray  # shape (K,) int: capture index
    names: list[str] = field(default_factory=list)
    source: str = "observations"
    source_sha256: str | None = None  # of the corner file's bytes as they were read (results.json inputs)
    approach: np.ndarray | None = None  # shape (K, D): +1/-1 per axis (default: the direction on every axis)
    mounted: tuple[Target, ...] | None = None  # SPEC 13 targets (None: one board)
    segment: np.ndarray | None = None  # (K,) int: a stitched capture's segment, one mounted target each (one board moved)
    repeatability_mm: float | None = None  # a stitched capture: the stage's repeatability (1 sigma) that ties segments
    corner_target: np.ndarray | None = None  # shape (N,) int: each corner's target (derived from ``mounted``)

    def __post_init__(self) -> None:
        self.corners_px = np.asarray(self.corners_px, dtype=float)
        K = self.corners_px.shape[0]
        target = np.asarray(self.target_mm, dtype=float)
        self.target_mm = target.reshape(K) if target.size == K else target.reshape(K, -1)  # (K, 1) is one axis
        self.direction = np.asarray(self.direction, dtype=float).reshape(K)
        self.run = np.asarray(self.run, dtype=int).reshape(K)
        self.index = np.asarray(self.index, dtype=int).reshape(K)
        if self.approach is None:
            self.approach = np.repeat(self.direction[:, None], self.D, axis=1)
        else:
            self.approach = np.asarray(self.approach, dtype=float).reshape(K, self.D)
        if not self.names:
            self.names = [f"view{i}" for i in self.index]
        if self.mounted is not None:
            self.mounted = tuple(self.mounted)
            self.corner_target = np.repeat(np.arange(len(self.mounted)), np.diff(target_offsets(list(self.mounted))))

    @property
    def n_corners_expected(self) -> int:
        """Corners of one view: the board's, or every target's laid end to end."""
        return self.board.n_corners if self.mounted is None else int(target_offsets(list(self.mounted))[-1])

    @property
    def D(self) -> int:
        """Number of stage axes: 1 (a line, SPEC 4) or 2 (a plane, SPEC 10)."""
        return 1 if self.target_mm.ndim == 1 else int(self.target_mm.shape[1])

    @property
    def targets(self) -> np.ndarray:
        """The targets as shape (K, D) whatever D is."""
        return self.target_mm.reshape(self.K, self.D)

    def subset(self, keep: np.ndarray) -> "Observations":
        """The views selected by a boolean mask or an index array."""
        keep = np.asarray(keep)
        idx = np.flatnonzero(keep) if keep.dtype == bool else keep
        return Observations(self.board, self.intrinsics, self.corners_px[idx], self.target_mm[idx],
                            self.direction[idx], self.run[idx], self.index[idx], [self.names[i] for i in idx],
                            self.source, approach=self.approach[idx], mounted=self.mounted,
                            segment=None if self.segment is None else self.segment[idx],
                            repeatability_mm=self.repeatability_mm)

    def validate(self) -> None:
        """Raise a one-line error when the views cannot determine the model of D axes."""
        if self.corners_px.ndim != 3 or self.corners_px.shape[2] != 2:
            raise InputError(f"{self.source}: corners must have shape (views, corners, 2)")
        if self.mounted is not None and self.N != self.n_corners_expected:
            raise InputError(f"{self.source}: views have {self.N} corners but the targets have "
                             f"{self.n_corners_expected}; check the targets in session.json")
        if self.mounted is None and self.N != self.board.n_corners:
            raise InputError(
                f"{self.source}: views have {self.N} corners but the board has {self.board.n_corners}; check inner_corners in board.json"
            )
        usable = self.usable_views()
        if usable.sum() < 3:
            need = "at different positions" if self.D == 1 else "at targets not on one line"
            raise DegenerateGeometryError(
                f"{self.source}: only {int(usable.sum())} views show the board; need at least 3 {need}"
            )
        t = self.targets[usable]
        sv = np.linalg.svd(t - t.mean(axis=0), compute_uv=False)  # the targets must span all D axes
        if sv.size < self.D or sv[self.D - 1] <= 1e-9 * max(sv[0], 1e-300):
            raise DegenerateGeometryError(f"{self.source}: {UNSPANNED[self.D]}")
