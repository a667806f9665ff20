"""Limits a capture plan is checked against before anything is built from it.

A plan's frame count follows from its numbers (``(stop - start) / step``),
so ``--stop 1e9 --step 1`` would build a billion stops before any other
check: counts are computed arithmetically and compared with the limits
first. Every field must also be a finite number of the right sign.
"""
from __future__ import annotations

import math
from typing import Any

from lps_gui.errors import InputError

MAX_FRAMES = 100_000  # a day of capture at one frame a second; a longer plan is almost surely a typo
MAX_RUNS = 1_000
MAX_FRAMES_PER_STOP = 1_000
MIN_SPACING_MM = 1e-4  # 0.1 um: closer targets are the same position for any camera
MAX_SETTLE_S = 3_600.0


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"plan: {name} must be a finite number, not {value!r}")
    return float(value)


def _count(name: str, value: Any, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= hi:
        raise InputError(f"plan: {name} must be a whole number from 1 to {hi}, not {value!r}")
    return value


def check_plan_fields(plan: Any) -> None:
    """InputError naming the first field of ``plan`` (a :class:`Plan`) that is out of range."""
    runs = _count("runs", plan.runs, MAX_RUNS)
    frames = _count("frames_per_stop", plan.frames_per_stop, MAX_FRAMES_PER_STOP)
    if _number("overshoot_mm", plan.overshoot_mm) < 0:
        raise InputError(f"plan: overshoot_mm is {plan.overshoot_mm:g}; give 0 or a positive distance")
    settle = _number("settle_s", plan.settle_s)
    if not 0 <= settle <= MAX_SETTLE_S:
        raise InputError(f"plan: settle_s is {settle:g}; give 0 to {MAX_SETTLE_S:g} s")
    if _number("feed_mm_min", plan.feed_mm_min) <= 0:
        raise InputError(f"plan: feed_mm_min is {plan.feed_mm_min:g}; give a positive feed (mm/min)")
    directions = 2 if plan.directions == "both" else 1
    if plan.targets_mm is None:
        start, stop, step = (_number(n, getattr(plan, n)) for n in ("start_mm", "stop_mm", "step_mm"))
        if step == 0 or (stop - start) / step < 0:
            raise InputError(f"plan: step {step} mm does not lead from {start} to {stop} mm")
        if abs(step) < MIN_SPACING_MM:
            raise InputError(f"plan: step {step:g} mm is below {MIN_SPACING_MM:g} mm; targets that close are one position")
        n_targets = math.floor(abs((stop - start) / step) + 0.5) + 1
        if n_targets < 2:
            raise InputError(f"plan: from {start:g} to {stop:g} mm by {step:g} is one target; give at least 2")
    else:
        targets = sorted(_number("targets_mm", t) for t in plan.targets_mm)
        n_targets = len(targets)
        if n_targets < 2:
            raise InputError("plan: give at least 2 targets")
        gaps = [b - a for a, b in zip(targets, targets[1:])]
        if targets[-1] - targets[0] < MIN_SPACING_MM or any(0 < g < MIN_SPACING_MM for g in gaps):
            raise InputError(f"plan: targets closer than {MIN_SPACING_MM:g} mm are one position; give targets at least "
                             f"that far apart (a repeated target is fine)")
    total = n_targets * directions * runs * frames
    if total > MAX_FRAMES:
        raise InputError(f"plan: {n_targets} targets x {directions} direction(s) x {runs} run(s) x {frames} frame(s) "
                         f"= {total} frames, over the limit of {MAX_FRAMES}; use a larger step or fewer runs")
