"""How the capture engine reaches a stop, and whether a plan fits the stage's travel (one or two axes).

On one axis each run is approached from an overshoot beyond its first
target, and again wherever the engine does not know where the stage came
from (:func:`approach_point_mm`). On an XY gantry (SPEC 10)
each axis is approached from the side the plan gives it
(:attr:`PlannedStop.approach`, ISO 230-2 per axis): an axis that must move
toward its target from that side moves straight there; one that would
arrive from the other side, or whose last approach was from the other side,
first goes to an overshoot point on its approach side. The axes move one
after the other (X, then Y), each a plain ``G1`` of one axis, so each
arrives from its own side whatever the other does.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from lps_gui.core.planning.plan import MOVE_TOL_MM, Plan, PlannedStop
from lps_gui.errors import InputError
from lps_gui.hardware.stage import Stage

PLANAR_AXES = ("X", "Y")


def format_target(target_mm: float | tuple[float, float]) -> str:
    """A target for messages: ``12.5 mm`` or ``(12.5, 30) mm``."""
    if isinstance(target_mm, tuple):
        return f"({target_mm[0]:g}, {target_mm[1]:g}) mm"
    return f"{target_mm:g} mm"


def approach_point_mm(plan: Plan, stop: PlannedStop, last_move: tuple | None) -> float | None:
    """One axis: where to go before the move onto ``stop`` so it is approached from its run's direction.

    None when the run goes on in its direction from the last stop
    (``last_move``: (run, direction, target, first index) of the stop the
    engine last reached, None after a pause, an error or at the start of a
    call) or when the plan has no overshoot.
    """
    sign = 1.0 if stop.direction == "+" else -1.0
    continues_run = (
        last_move is not None
        and last_move[:2] == (stop.run, stop.direction)
        and (stop.target_mm - last_move[2]) * sign > 0
    )
    if continues_run or not plan.overshoot_mm > 0:
        return None
    return plan.approach_start_mm(stop.direction, stop.target_mm)


def axis_moves(here_mm: tuple[float, float], sides: list[int | None], stop: PlannedStop, overshoot_mm: float
               ) -> list[tuple[str, float]]:
    """The single-axis moves that bring the carriage onto ``stop`` from its approach sides.

    ``sides`` holds each axis' side of its last approach (None: unknown, e.g.
    after a pause); it is updated in place.
    """
    moves: list[tuple[str, float]] = []
    for a, name in enumerate(PLANAR_AXES):
        target, side = stop.target_mm[a], stop.approach[a]
        delta = target - here_mm[a]
        if abs(delta) <= MOVE_TOL_MM and sides[a] == side:
            continue  # already there, approached from the right side
        if delta * side <= MOVE_TOL_MM:  # it would arrive from the other side (or not move at all)
            moves.append((name, target - side * max(overshoot_mm, 0.0)))  # come round from the approach side
        moves.append((name, target))
        sides[a] = side
    return moves


def go_to_planar(stage: Stage, stop: PlannedStop, plan: Plan, sides: list[int | None],
                 move: Callable[[float, float, str], None]) -> tuple[float, float]:
    """Move onto ``stop`` (axis by axis, each from its side); returns the reported (x, y) in mm."""
    here = (float(stage.position_mm("X")), float(stage.position_mm("Y")))
    for axis, target in axis_moves(here, sides, stop, plan.overshoot_mm):
        move(target, plan.feed_mm_min, axis)
    return (float(stage.position_mm("X")), float(stage.position_mm("Y")))


def check_plan_in_travel(plan: Plan, stage: Stage) -> None:
    """InputError before any move when a target or overshoot lies outside the stage's known travel.

    Only stages that know their travel (``Stage.travel_mm``, ``axis_travel_mm``: the simulated one) can be
    checked here; a controller that guards its own soft limits raises an alarm at the offending move.
    """
    t = plan.targets()
    if not plan.planar:
        travel = stage.travel_mm
        if travel is None:
            return
        lo, hi = float(t[0]) - plan.overshoot_mm, float(t[-1]) + plan.overshoot_mm
        if lo < travel[0] or hi > travel[1]:
            raise InputError(
                f"plan: moves from {lo:g} to {hi:g} mm (targets and overshoot) but the stage travels "
                f"{travel[0]:g}..{travel[1]:g} mm; shorten the plan or the overshoot"
            )
        return
    axis_travel = stage.axis_travel_mm
    if axis_travel is None:
        return
    for a, name in enumerate(PLANAR_AXES):
        lo, hi = float(np.min(t[:, a])) - plan.overshoot_mm, float(np.max(t[:, a])) + plan.overshoot_mm
        t_lo, t_hi = axis_travel[a]
        if lo < t_lo or hi > t_hi:
            raise InputError(f"plan: {name} moves from {lo:g} to {hi:g} mm (targets and overshoot) but the stage's {name} "
                             f"travels {t_lo:g}..{t_hi:g} mm; shorten the plan or the overshoot")
