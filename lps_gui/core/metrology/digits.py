"""A figure printed with its significant digits: one rule for the report, the verdict notes and the console.

The verdict rows (``core.metrology.verdict``) write numbers into their notes and the report prints
the same numbers beside them, so both format through here.
"""
from __future__ import annotations

import math

import numpy as np

DASH = "\u2014"
ZERO_BELOW = 1e-9  # |values| below this print as 0 (no unit of the report resolves them)


def fmt(value: float | None, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (no exponent for usual sizes); a dash for None/NaN."""
    if value is None or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
        return DASH
    v = float(value)
    if abs(v) < ZERO_BELOW:
        return "0"  # rounding noise of a difference (e.g. an Abbe term of 6e-12 um) reads as what it is
    mag = int(math.floor(math.log10(abs(v))))
    if mag >= 6 or mag < -4:
        return f"{v:.{digits - 1}e}"
    decimals = max(0, digits - 1 - mag)
    return f"{v:.{decimals}f}"
