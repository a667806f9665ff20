"""Axis ranges and tick positions for the report plots (pure numpy, no Qt).

Ticks fall on 1, 2, 5 x 10^k so a printed axis reads at a glance; a log
axis (the error spectrum's period) puts ticks on decades and 2, 5 in between.
"""
from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from lps_gui.report.figures.spec import FigureSpec


def data_range(figure: FigureSpec, axis: str) -> tuple[float, float] | None:
    """Finite (min, max) over every series of ``figure`` along ``axis`` ("x" or "y"); bands included."""
    chunks: list[np.ndarray] = []
    for s in figure.series:
        arrays: Iterable[np.ndarray | None] = (s.x,) if axis == "x" else (s.y, s.band_low, s.band_high)
        for a in arrays:
            if a is not None and len(a):
                a = np.asarray(a, dtype=float)
                if axis == "x" and figure.x_log:
                    a = a[a > 0]
                chunks.append(a[np.isfinite(a)])
    values = np.concatenate(chunks) if chunks else np.zeros(0)
    if values.size == 0:
        return None
    return float(values.min()), float(values.max())


def padded(lo: float, hi: float, fraction: float = 0.05, log: bool = False) -> tuple[float, float]:
    """Widen (lo, hi) by ``fraction`` each side; a flat range gets a unit-ish span."""
    if log:
        lo, hi = math.log10(lo), math.log10(hi)
        if hi - lo < 1e-9:
            lo, hi = lo - 0.5, hi + 0.5
        pad = (hi - lo) * fraction
        return 10 ** (lo - pad), 10 ** (hi + pad)
    if hi - lo < 1e-12 * max(1.0, abs(hi)):
        half = max(abs(hi) * 0.05, 1.0)
        return lo - half, hi + half
    pad = (hi - lo) * fraction
    return lo - pad, hi + pad


def nice_ticks(lo: float, hi: float, target: int = 6) -> np.ndarray:
    """Tick positions on 1/2/5 x 10^k inside [lo, hi], about ``target`` of them."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return np.array([lo])
    raw = (hi - lo) / max(target, 1)
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = math.ceil(lo / step - 1e-9) * step
    ticks = np.arange(first, hi + step * 1e-9, step)
    return np.where(np.abs(ticks) < step * 1e-9, 0.0, ticks)


def log_ticks(lo: float, hi: float) -> np.ndarray:
    """Ticks at 1, 2, 5 x 10^k inside [lo, hi] (both > 0)."""
    out = []
    for k in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1):
        for m in (1, 2, 5):
            v = m * 10.0**k
            if lo <= v <= hi:
                out.append(v)
    return np.array(out)


def tick_label(value: float, ticks: np.ndarray) -> str:
    """A tick's text with as many decimals as the tick spacing needs."""
    if ticks.size > 1:
        step = float(np.min(np.diff(ticks)))
        decimals = next((d for d in range(8) if abs(step * 10**d - round(step * 10**d)) < 1e-6 * step * 10**d), 8)
    else:
        decimals = 2
    if abs(value) >= 1e5 or (value != 0 and abs(value) < 1e-4):
        return f"{value:.1e}"
    return f"{value:.{decimals}f}".replace("-", "\u2212")
