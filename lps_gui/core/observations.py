"""The estimators' input: corners of K views of one board, with capture metadata."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.errors import DegenerateGeometryError, InputError

MIN_CORNERS_PER_VIEW = 6


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
    """Corners of K views (NaN where missing) and what the stage was told to do."""

    board: Board
    intrinsics: CameraIntrinsics
    corners_px: np.ndarray  # shape (K, N, 2)
    target_mm: np.ndarray  # shape (K,)
    direction: np.ndarray  # shape (K,): +1 forward, -1 backward
    run: np.ndarray  # shape (K,) int
    index: np.ndarray  # shape (K,) int: capture index
    names: list[str] = field(default_factory=list)
    source: str = "observations"
    source_sha256: str | None = None  # of the corner file's bytes as they were read (results.json inputs)

    def __post_init__(self) -> None:
        self.corners_px = np.asarray(self.corners_px, dtype=float)
        K = self.corners_px.shape[0]
        self.target_mm = np.asarray(self.target_mm, dtype=float).reshape(K)
        self.direction = np.asarray(self.direction, dtype=float).reshape(K)
        self.run = np.asarray(self.run, dtype=int).reshape(K)
        self.index = np.asarray(self.index, dtype=int).reshape(K)
        if not self.names:
            self.names = [f"view{i}" for i in self.index]


    def subset(self, keep: np.ndarray) -> "Observations":
        """The views selected by a boolean mask or an index array."""
        keep = np.asarray(keep)
        idx = np.flatnonzero(keep) if keep.dtype == bool else keep
        return Observations(
            self.board,
            self.intrinsics,
            self.corners_px[idx],
            self.target_mm[idx],
            self.direction[idx],
            self.run[idx],
            self.index[idx],
            [self.names[i] for i in idx],
            self.source,
        )

    def validate(self) -> None:
        """Raise a one-line error when the views cannot determine the LPS model."""
        if self.corners_px.ndim != 3 or self.corners_px.shape[2] != 2:
            raise InputError(f"{self.source}: corners must have shape (views, corners, 2)")
        if self.N != self.board.n_corners:
            raise InputError(
                f"{self.source}: views have {self.N} corners but the board has {self.board.n_corners}; check inner_corners in board.json"
            )
        usable = self.usable_views()
        if usable.sum() < 3:
            raise DegenerateGeometryError(
                f"{self.source}: only {int(usable.sum())} views show the board; need at least 3 at different positions"
            )
        t = self.target_mm[usable]
        if np.ptp(t) <= 0:
            raise DegenerateGeometryError(
                f"{self.source}: all views are at one target position; the line direction is undetermined, capture along the axis"
            )
