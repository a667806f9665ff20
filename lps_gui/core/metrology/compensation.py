"""Compensation tables from measured positions: what a controller needs to land on the nominal.

A table maps the commanded (nominal) position x to where the carriage really
ends up, per approach direction: ``actual_plus(x)`` moving up, ``actual_minus(x)``
moving down (LinuxCNC's COMP_FILE_TYPE 0 columns). Measured positions are
relative to the reference capture (SPEC 5), so the table carries a free
offset: zero deviation at the reference. Between grid points it is linear,
as every controller interpolates it.

Uncertainty: each position's sigma in results.json contains the reference
capture's own noise, which is common to every entry and leaves with the free
offset; :func:`own_sigma_um` takes it out so the entry sigma is what a
comparison after removing the offset sees. Several runs add their scatter.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.errors import InputError

MAX_POINTS = 256  # LinuxCNC: "256 triplets per joint"


@dataclass(frozen=True)
class CompensationTable:
    """Actual position per commanded position and direction on a regular grid (mm, sigma um)."""

    nominal_mm: np.ndarray  # shape (M,), ascending, regular
    actual_plus_mm: np.ndarray  # shape (M,): reached moving in +
    actual_minus_mm: np.ndarray  # shape (M,): reached moving in -
    sigma_plus_um: np.ndarray  # shape (M,)
    sigma_minus_um: np.ndarray  # shape (M,)
    bidirectional: bool  # False: one direction measured, its column repeated

    def __post_init__(self) -> None:
        x = np.asarray(self.nominal_mm, dtype=float)
        if x.ndim != 1 or len(x) < 2 or np.any(np.diff(x) <= 0):
            raise InputError("compensation table: needs at least 2 nominal positions in ascending order")
        if len(x) > MAX_POINTS:
            raise InputError(f"compensation table: {len(x)} points; controllers take at most {MAX_POINTS}")

    def offset_um(self, direction: int) -> np.ndarray:
        """actual - nominal on the grid for ``direction`` (+1/-1), um."""
        actual = self.actual_plus_mm if direction > 0 else self.actual_minus_mm
        return 1e3 * (np.asarray(actual) - np.asarray(self.nominal_mm))

    def actual_mm(self, commanded_mm: np.ndarray | float, direction: int) -> np.ndarray:
        """Where the carriage ends up when commanded to ``commanded_mm`` (linear between points, constant outside)."""
        x = np.asarray(commanded_mm, dtype=float)
        return x + 1e-3 * np.interp(x, self.nominal_mm, self.offset_um(direction))

    def command_mm(self, nominal_mm: np.ndarray | float, direction: int) -> np.ndarray:
        """The commanded position whose actual position is ``nominal_mm``: the table's inverse.

        Fixed-point iteration c <- x - offset(c); it contracts because the
        offset changes by far less than the position (slope << 1).
        """
        x = np.asarray(nominal_mm, dtype=float)
        off = self.offset_um(direction)
        c = x.copy()
        for _ in range(30):
            c_new = x - 1e-3 * np.interp(c, self.nominal_mm, off)
            if np.all(np.abs(c_new - c) < 1e-9):
                return c_new
            c = c_new
        return c

    def backlash_um(self) -> float | None:
        """Mean reversal, actual moving down minus actual moving up (positive: lost motion); None unidirectional."""
        if not self.bidirectional:
            return None
        return float(np.mean(1e3 * (np.asarray(self.actual_minus_mm) - np.asarray(self.actual_plus_mm))))

    def to_dict(self) -> dict:
        return {
            "nominal_mm": np.asarray(self.nominal_mm).tolist(),
            "actual_plus_mm": np.asarray(self.actual_plus_mm).tolist(),
            "actual_minus_mm": np.asarray(self.actual_minus_mm).tolist(),
            "sigma_plus_um": np.asarray(self.sigma_plus_um).tolist(),
            "sigma_minus_um": np.asarray(self.sigma_minus_um).tolist(),
            "bidirectional": bool(self.bidirectional),
        }

    @classmethod
    def from_dict(cls, d: dict) -> "CompensationTable":
        try:
            return cls(*(np.asarray(d[k], dtype=float) for k in
                         ("nominal_mm", "actual_plus_mm", "actual_minus_mm", "sigma_plus_um", "sigma_minus_um")),
                       bidirectional=bool(d.get("bidirectional", True)))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"compensation table: {type(exc).__name__} {exc}; write it again with `lps compensate`") from exc


def own_sigma_um(sigma_um: np.ndarray, is_reference: np.ndarray) -> np.ndarray:
    """Per-position sigma without the reference capture's noise (common to all, removed with the offset).

    With the gauge s_ref = 0 each s_i = p_i - p_ref, so var(s_i) = var(p_i) +
    var(p_ref); var(p_ref) is taken as half the median variance (views of one
    session are alike). The reference itself gets that own sigma.
    """
    s = np.asarray(sigma_um, dtype=float)
    ok = np.isfinite(s) & (s > 0) & ~np.asarray(is_reference, dtype=bool)
    if not ok.any():
        return np.where(np.isfinite(s), s, np.nan)
    ref_var = 0.5 * float(np.median(s[ok] ** 2))
    own = np.sqrt(np.maximum(s**2 - ref_var, 0.25 * s**2))
    return np.where(np.asarray(is_reference, dtype=bool), np.sqrt(ref_var), own)


def target_means(target: np.ndarray, dev_um: np.ndarray, sigma_um: np.ndarray, run: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Targets, mean deviation over runs and its sigma (noise, or the pooled run scatter when larger)."""
    targets = np.unique(target)
    idx = np.searchsorted(targets, target)
    n = np.bincount(idx, minlength=len(targets)).astype(float)
    mean = np.bincount(idx, weights=dev_um, minlength=len(targets)) / n
    noise_var = np.bincount(idx, weights=sigma_um**2, minlength=len(targets)) / n
    resid = dev_um - mean[idx]
    dof = float(np.sum(n - 1))
    pooled_var = float(np.sum(resid**2) / dof) if dof >= 1 else 0.0
    sigma = np.sqrt(np.maximum(noise_var, pooled_var) / n)
    return targets, mean, sigma


def _regular(values: np.ndarray) -> bool:
    d = np.diff(values)
    return len(values) >= 2 and bool(np.allclose(d, d[0], rtol=1e-6, atol=1e-9))


def _resample(x: np.ndarray, grid: np.ndarray, value: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation of value onto grid; sigma of the interpolated (independent) entries."""
    j = np.clip(np.searchsorted(x, grid, side="right") - 1, 0, len(x) - 2)
    w = np.clip((grid - x[j]) / (x[j + 1] - x[j]), 0.0, 1.0)
    v = (1 - w) * value[j] + w * value[j + 1]
    s = np.sqrt(((1 - w) * sigma[j]) ** 2 + (w * sigma[j + 1]) ** 2)
    return v, s


def build_table(
    target_mm: np.ndarray,
    direction: np.ndarray,
    run: np.ndarray,
    deviation_um: np.ndarray,
    sigma_um: np.ndarray,
    valid: np.ndarray,
    max_points: int = MAX_POINTS,
) -> CompensationTable:
    """The table from per-capture deviations (measured - target, um, zero at the reference).

    The grid is the plan's targets when they are regular, shared by both
    directions and at most ``max_points``; otherwise a regular grid over the
    common range with as many points as targets (at most ``max_points``),
    linearly interpolated.
    """
    t = np.asarray(target_mm, dtype=float)
    d = np.sign(np.asarray(direction, dtype=float))
    dev = np.asarray(deviation_um, dtype=float)
    sig = np.asarray(sigma_um, dtype=float)
    ok = np.asarray(valid, dtype=bool) & np.isfinite(dev) & np.isfinite(sig)
    columns = {}
    for sign in (1, -1):
        m = ok & (d == sign)
        if np.unique(t[m]).size >= 2:
            columns[sign] = target_means(t[m], dev[m], sig[m], np.asarray(run)[m])
    if not columns:
        raise InputError("compensation: fewer than 2 measured targets in any direction; measure more targets")
    lo = max(c[0][0] for c in columns.values())
    hi = min(c[0][-1] for c in columns.values())
    if hi <= lo:
        raise InputError("compensation: the two directions' targets do not overlap; measure both over one range")
    first = next(iter(columns.values()))[0]
    same = all(np.array_equal(c[0], first) for c in columns.values())
    if same and _regular(first) and len(first) <= max_points:
        grid = first
    else:
        n_targets = max(len(c[0]) for c in columns.values())
        grid = np.linspace(lo, hi, int(min(max(n_targets, 2), max_points)))
    per_dir = {sign: _resample(x, grid, v, s) for sign, (x, v, s) in columns.items()}
    plus = per_dir.get(1, per_dir.get(-1))
    minus = per_dir.get(-1, per_dir.get(1))
    return CompensationTable(
        nominal_mm=grid,
        actual_plus_mm=grid + 1e-3 * plus[0],
        actual_minus_mm=grid + 1e-3 * minus[0],
        sigma_plus_um=plus[1],
        sigma_minus_um=minus[1],
        bidirectional=len(per_dir) == 2,
    )


def skew_factor(squareness_urad: float) -> float:
    """XY skew factor (tan of the deviation from 90 degrees) as Marlin's M852 and Klipper take it.

    ``squareness_urad`` > 0: the axes enclose less than 90 degrees.
    """
    return float(np.tan(1e-6 * squareness_urad))


def skew_square_lengths(squareness_urad: float, side_mm: float = 100.0) -> tuple[float, float, float]:
    """Diagonals AC, BD and side AD of the square a skewed machine prints (Klipper SET_SKEW XY=AC,BD,AD).

    A square of side ``side_mm`` commanded on axes enclosing 90 deg - gamma
    becomes a rhombus; Klipper's and Marlin's formula
    tan(pi/2 - acos((AC^2 - AB^2 - AD^2) / (2 AB AD))) with
    AB = sqrt(2 AC^2 + 2 BD^2 - 4 AD^2) / 2 returns tan(gamma) from these.
    """
    g = 1e-6 * squareness_urad
    L = float(side_mm)
    angle = 0.5 * np.pi + g  # angle at corner B, opposite AC: the formula returns tan(B - 90 deg)
    ac = float(np.sqrt(2 * L * L * (1 - np.cos(angle))))
    bd = float(np.sqrt(2 * L * L * (1 + np.cos(angle))))
    return ac, bd, L
