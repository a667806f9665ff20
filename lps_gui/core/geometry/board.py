"""Calibration boards: geometry only (detection lives with the images)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.errors import InputError

BOARD_TYPES = ("chessboard", "charuco")


def parabolic_warp_basis(xy_mm: np.ndarray, size_mm: tuple[float, float]) -> np.ndarray:
    """(1 - x^2, 1 - y^2) with x, y scaled so a grid of ``size_mm`` (from the origin) spans [-1, 1]; shape (..., 2)."""
    xy = np.asarray(xy_mm, dtype=float)
    xn = 2.0 * xy[..., 0] / size_mm[0] - 1.0
    yn = 2.0 * xy[..., 1] / size_mm[1] - 1.0
    return np.stack([1.0 - xn * xn, 1.0 - yn * yn], axis=-1)


@dataclass(frozen=True)
class Board:
    """A planar board; ``inner_corners`` is (cols, rows), OpenCV patternSize order.

    Corner (r, c) sits at X = (c*s, r*s, 0) mm with index r*cols + c (SPEC 2).
    For a ChArUco board the corners are its inner chessboard corners, in the
    same order; ``marker_mm`` and ``dictionary`` describe the markers.

    ``warp_mm`` = (bow_x, bow_y): the board's deviation from flat as mrcal
    models it (``calobject_warp``): with the corner grid spanning [-1, 1]
    along each axis, corner z = bow_x (1 - x^2) + bow_y (1 - y^2) mm, so
    bow_x is how far the centre line stands off the x-edges. None = flat.
    """

    cols: int
    rows: int
    square_mm: float
    type: str = "chessboard"
    marker_mm: float | None = None
    dictionary: str | None = None
    warp_mm: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.type not in BOARD_TYPES:
            raise InputError(f"board: unknown type {self.type!r}; use one of {', '.join(BOARD_TYPES)}")
        if self.cols < 2 or self.rows < 2:
            raise InputError(f"board: inner_corners {self.cols}x{self.rows} is too small; need at least 2x2")
        if not self.square_mm > 0:
            raise InputError(f"board: square_mm must be positive, got {self.square_mm}")
        if self.warp_mm is not None:
            warp = tuple(float(v) for v in self.warp_mm)
            if len(warp) != 2 or not all(np.isfinite(warp)):
                raise InputError(f"board: warp_mm must be two finite numbers [bow_x, bow_y], got {self.warp_mm!r}")
            object.__setattr__(self, "warp_mm", warp)

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

    def flat_points(self) -> np.ndarray:
        """Board-frame corner coordinates of the flat board, shape (rows*cols, 3) mm, row-major."""
        r, c = np.mgrid[0 : self.rows, 0 : self.cols]
        pts = np.zeros((self.rows * self.cols, 3))
        pts[:, 0] = c.ravel() * self.square_mm
        pts[:, 1] = r.ravel() * self.square_mm
        return pts

    def warp_basis(self, xy_mm: np.ndarray) -> np.ndarray:
        """d z / d (bow_x, bow_y) at board points (..., >=2) mm: (1 - x^2, 1 - y^2), shape (..., 2).

        x, y are the point's coordinates scaled so the inner-corner grid
        spans [-1, 1] (mrcal's calobject_warp convention).
        """
        return parabolic_warp_basis(xy_mm, self.size_mm)

    def warp_z(self, xy_mm: np.ndarray) -> np.ndarray:
        """Out-of-plane offset z (mm) of the board surface at board points (..., >=2) mm."""
        if self.warp_mm is None:
            return np.zeros(np.shape(xy_mm)[:-1])
        return self.warp_basis(xy_mm) @ np.asarray(self.warp_mm)

    def object_points(self) -> np.ndarray:
        """Board-frame corner coordinates, shape (rows*cols, 3) mm, row-major; warped when ``warp_mm`` is set."""
        pts = self.flat_points()
        if self.warp_mm is not None:
            pts[:, 2] = self.warp_z(pts)
        return pts

    def centre_mm(self) -> np.ndarray:
        """Centre of the corner grid in the board frame, shape (3,)."""
        w, h = self.size_mm
        return np.array([w / 2.0, h / 2.0, 0.0])
