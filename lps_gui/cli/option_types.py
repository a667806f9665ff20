"""argparse ``type=`` checks shared by every command's numeric options.

``float("nan")``, ``inf``, 0 or a negative count parse fine and then turn a
check off (``x > k`` is never true for NaN), run for ever or allocate without
bound; these types refuse them while the command line is parsed, so the user
gets argparse's one line naming the option before anything is read or written.
"""
from __future__ import annotations

import argparse
import math
from typing import Callable

MAX_ABS = 1e9  # no option of lps is meaningful beyond this (mm, um, px, s, urad)


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None


def finite(text: str) -> float:
    """Any finite number of sensible size."""
    value = _number(text)
    if abs(value) > MAX_ABS:
        raise argparse.ArgumentTypeError(f"{text} is out of range (|x| <= {MAX_ABS:g})")
    return value


def positive_finite(text: str) -> float:
    """A finite number > 0 (sizes, spacings, thresholds, sigmas)."""
    value = finite(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be greater than 0, got {text}")
    return value


def nonnegative_finite(text: str) -> float:
    """A finite number >= 0 (noise, settle times)."""
    value = finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, got {text}")
    return value


def fraction(text: str) -> float:
    """A fraction from 0 to 1."""
    value = _number(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be a fraction from 0 to 1, got {text}")
    return value


def int_range(lo: int, hi: int) -> Callable[[str], int]:
    """A whole number from ``lo`` to ``hi``."""

    def check(text: str) -> int:
        value = _whole(text)
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be a whole number, at least {lo} and at most {hi}, got {text}")
        return value

    check.__name__ = f"int {lo}..{hi}"
    return check


def float_range(lo: float, hi: float, low_open: bool = False) -> Callable[[str], float]:
    """A finite number from ``lo`` (excluded when ``low_open``) to ``hi``."""

    def check(text: str) -> float:
        value = _number(text)
        if not (value > lo if low_open else value >= lo) or value > hi:
            raise argparse.ArgumentTypeError(f"must be {'over' if low_open else 'at least'} {lo:g} and at most "
                                             f"{hi:g}, got {text}")
        return value

    check.__name__ = f"number {lo:g}..{hi:g}"
    return check


positive_int = int_range(1, 10**9)
nonnegative_int = int_range(0, 2**32 - 1)  # seeds: numpy takes 0..2**32-1
workers = int_range(1, 256)
