"""Does the lens model fit? Reprojection residuals binned over the image (issue 35).

Corner noise averages out within a bin; a lens the model cannot follow does
not: it leaves a smooth field of residuals over the image. The binned mean
residual is tested against what noise alone gives (chi-square over the bins,
the noise taken from second differences of neighbouring corners, where a smooth
misfit cancels), and the residual's RMS beyond that noise is the *misfit*: the
field that no pose or intrinsics of this model takes out (each view's pose
absorbs a different part of it, so its mean over the views understates it). A misfit
above the corner noise is flagged, naming the richer model to calibrate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

BINS = (4, 4)  # (cols, rows) of the structure test
NOISE_GRID = (16, 12)  # (cols, rows) of the cells whose inner scatter is the corner noise
MIN_PER_BIN = 8  # corners a bin needs to be judged
P_VALUE = 1e-3  # a structure is significant at this level
RECALIBRATE = ("recalibrate with `lps intrinsics --model rational` (rational and thin-prism terms) and "
               "estimate with the new intrinsics")


def _cells(uv: np.ndarray, image_size: tuple[int, int], grid: tuple[int, int]) -> np.ndarray:
    """Flat cell index (row-major over (rows, cols)) of each pixel."""
    w, h = image_size
    c = np.clip((uv[:, 0] / w * grid[0]).astype(int), 0, grid[0] - 1)
    r = np.clip((uv[:, 1] / h * grid[1]).astype(int), 0, grid[1] - 1)
    return r * grid[0] + c


def _cell_means(uv: np.ndarray, res: np.ndarray, image_size: tuple[int, int], grid: tuple[int, int]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per cell: count (G,), mean residual (G, 2), and each corner's cell index."""
    cell = _cells(uv, image_size, grid)
    n = grid[0] * grid[1]
    count = np.bincount(cell, minlength=n).astype(float)
    mean = np.stack([np.bincount(cell, weights=res[:, a], minlength=n) for a in (0, 1)], axis=1)
    return count, mean / np.maximum(count, 1.0)[:, None], cell


@dataclass(frozen=True)
class ResidualStructure:
    """Binned mean residuals over the image and the verdict on them."""

    mean_px: np.ndarray  # (rows, cols, 2) mean residual of each bin
    count: np.ndarray  # (rows, cols) corners of each bin
    noise_px: float  # corner noise per axis (second differences, or the scatter within fine cells)
    misfit_px: float  # RMS length of the residual beyond the corner noise (smooth within a view, so a model's)
    chi2: float
    dof: int

    @property
    def p_value(self) -> float:
        from lps_gui.core.metrology.resolution import chi2_sf

        return chi2_sf(self.chi2, self.dof) if self.dof > 0 else 1.0

    @property
    def significant(self) -> bool:
        """The binned means are not zero beyond noise (at :data:`P_VALUE`)."""
        return self.dof > 0 and self.p_value < P_VALUE

    @property
    def exceeds_noise(self) -> bool:
        """Flagged: a significant structure whose size exceeds the corner noise."""
        return self.significant and self.misfit_px > self.noise_px

    def to_dict(self) -> dict[str, Any]:
        return {"misfit_px": self.misfit_px, "noise_px": self.noise_px, "chi2": self.chi2, "dof": self.dof,
                "bins": list(BINS), "mean_px": np.round(self.mean_px, 5).tolist(), "count": self.count.tolist(),
                "flagged": self.exceeds_noise}

    def message(self, what: str) -> str:
        return (f"lens model does not fit {what}: the residuals leave {self.misfit_px:.3f} px RMS beyond the corner "
                f"noise of {self.noise_px:.3f} px, structured over the image (chi-square {self.chi2:.0f} on {self.dof} dof "
                f"of {BINS[0]}x{BINS[1]} bins); tilts from one target plane are then not resolved; "
                f"{RECALIBRATE}")


def second_difference_noise(residuals: np.ndarray, row_of: np.ndarray) -> float | None:
    """Corner noise per axis from second differences of neighbouring corners along the board's rows.

    ``residuals`` (V, N, 2), ``row_of`` (N,) the board row of each corner (consecutive corners of one row
    are neighbours). A smooth misfit field cancels in r[i-1] - 2 r[i] + r[i+1]; independent noise of
    variance s^2 gives 6 s^2. None without three neighbours seen anywhere.
    """
    r = np.asarray(residuals, float)
    row = np.asarray(row_of)
    same = (row[:-2] == row[1:-1]) & (row[1:-1] == row[2:])
    d2 = (r[:, :-2] - 2.0 * r[:, 1:-1] + r[:, 2:])[:, same]
    d2 = d2[np.all(np.isfinite(d2), axis=-1)]
    if d2.size == 0:
        return None
    return math.sqrt(float(np.mean(d2**2)) / 6.0)


def residual_structure(uv: np.ndarray, residuals: np.ndarray, image_size: tuple[int, int],
                       row_of: np.ndarray | None = None) -> ResidualStructure | None:
    """The residual structure of corners at ``uv`` (V, N, 2) px with residuals (V, N, 2) px (NaN: not seen).

    The corner noise comes from second differences along the board's rows when ``row_of`` (N,) gives
    them (a misfit that each view's pose takes out differently does not enter it), else from the scatter
    within fine cells. None when too few corners to judge (fewer than two bins with :data:`MIN_PER_BIN`).
    """
    uv3 = np.asarray(uv, float)
    res3 = np.asarray(residuals, float)
    noise = None if row_of is None else second_difference_noise(res3.reshape((-1,) + res3.shape[-2:]), row_of)
    uv, res = uv3.reshape(-1, 2), res3.reshape(-1, 2)
    ok = np.all(np.isfinite(uv), axis=1) & np.all(np.isfinite(res), axis=1)
    uv, res = uv[ok], res[ok]
    if noise is None:
        fine_n, fine_mean, fine_cell = _cell_means(uv, res, image_size, NOISE_GRID)
        dof_noise = 2.0 * (len(uv) - np.count_nonzero(fine_n))
        if dof_noise <= 0:
            return None
        noise = math.sqrt(float(np.sum((res - fine_mean[fine_cell]) ** 2)) / dof_noise)
    count, mean, _ = _cell_means(uv, res, image_size, BINS)
    judged = count >= MIN_PER_BIN
    if judged.sum() < 2 or noise <= 0:
        return None
    chi2 = float(np.sum(count[judged] * np.sum(mean[judged] ** 2, axis=1)) / noise**2)
    excess = float(np.mean(np.sum(res**2, axis=1))) - 2.0 * noise**2  # what noise does not explain (2-D)
    shape = (BINS[1], BINS[0])
    return ResidualStructure(mean.reshape(shape + (2,)), count.reshape(shape).astype(int), noise,
                             math.sqrt(max(float(excess), 0.0)), chi2, int(2 * judged.sum()))
