"""Calibration boards: geometry only (detection lives with the images)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.errors import InputError

BOARD_TYPES = ("chessboard", "charuco")


@dataclass(frozen=True)
class Board:
    """A planar board; ``inner_corners`` is (cols, rows), OpenCV patternSize order.

    Corner (r, c) sits at X = (c*s, r*s, 0) mm with index r*cols + c (SPEC 2).
    For a ChArUco board the corners are its inner chessboard corners, in the
    same order; ``marker_mm`` and ``dictionary`` describe the markers.
    """

    cols: int
    rows: int
    square_mm: float
    type: str = "chessboard"
    marker_mm: float | None = None
    dictionary: str | None = None

    def __post_init__(self) -> None:
        if self.type not in BOARD_TYPES:
            raise InputError(f"board: unknown type {self.type!r}; use one of {', '.join(BOARD_TYPES)}")
        if self.cols < 2 or self.rows < 2:
            raise InputError(f"board: inner_corners {self.cols}x{self.rows} is too small; need at least 2x2")
        if not self.square_mm > 0:
            raise InputError(f"board: square_mm must be positive, got {self.square_mm}")

    @property
    def inner_corners(self) -> tuple[int, int]:
        return (self.cols, self.rows)

    @property
    def n_corners(self) -> int:
        return self.cols * self.rows

    @property
    def size_mm(self) -> tuple[float, float]:
        """Extent of the inner-corner grid (width, height) in mm."""
        return ((self.cols - 1) * self.square_mm, (self.rows - 1) * self.square_mm)

    def object_points(self) -> np.ndarray:
        """Board-frame corner coordinates, shape (rows*cols, 3) mm, row-major."""
        r, c = np.mgrid[0 : self.rows, 0 : self.cols]
        pts = np.zeros((self.rows * self.cols, 3))
        pts[:, 0] = c.ravel() * self.square_mm
        pts[:, 1] = r.ravel() * self.square_mm
        return pts

    def centre_mm(self) -> np.ndarray:
        """Centre of the corner grid in the board frame, shape (3,)."""
        w, h = self.size_mm
        return np.array([w / 2.0, h / 2.0, 0.0])
