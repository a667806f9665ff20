"""A controller's motion planner for the simulated stage: queued profiles, controlled stops, held moves.

Moves are planned back to back (each starts when the previous one ends, from
where it ends) in a buffer of :data:`PLANNER_BLOCKS` blocks, as a controller's ring buffer.
A feed hold or jog cancel replaces the running profile by its deceleration;
a hold keeps what was cut short for :meth:`MotionPlanner.resume`. Everything
is evaluated at a clock time, so nothing ticks. Not thread-safe: the owning
stage holds its lock around every call.
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from lps_gui.hardware.motion import Profile, stop_from, trapezoid

PLANNER_BLOCKS = 15  # a 16-block ring buffer, one always empty (the GRBL emulator reports it as Bf:15 when idle)


class HeldMove(NamedTuple):
    """A move cut short by a feed hold, to be planned again on resume."""

    axis: int
    kind: str
    target_mm: float
    feed_mm_min: float


class MotionPlanner:
    """Queue of one-axis :class:`Profile` objects over a resting position ``pos_mm`` (shape (3,))."""

    def __init__(self, pos_mm: np.ndarray, blocks: int = PLANNER_BLOCKS) -> None:
        self.pos_mm = np.asarray(pos_mm, dtype=float).copy()  # shape (3,): where each axis rests
        self.blocks = blocks
        self.queue: list[Profile] = []
        self.stopping: Profile | None = None  # deceleration of a hold or jog cancel
        self.held: list[HeldMove] = []
        self.hold = False

    # ------------------------------------------------------------------ evaluation
    def update(self, t: float) -> list[Profile]:
        """Retire the profiles finished by time ``t``; return them in order."""
        done = []
        if self.stopping is not None and t >= self.stopping.t_end:
            done.append(self.stopping)
            self.stopping = None
        while self.queue and t >= self.queue[0].t_end:
            done.append(self.queue.pop(0))
        for p in done:
            self.pos_mm[p.axis] = p.end_mm
        return done

    def active(self) -> Profile | None:
        """The profile moving the carriage now (after :meth:`update`), or None."""
        return self.stopping if self.stopping is not None else (self.queue[0] if self.queue else None)

    def state(self) -> tuple[str, int | None]:
        """The motion's state: Hold with substate 1 (stopping) / 0 (stopped), the active profile's kind, or Idle."""
        if self.hold:
            return "Hold", (1 if self.stopping is not None else 0)
        p = self.active()
        return (p.kind, None) if p is not None else ("Idle", None)

    def positions(self, t: float) -> tuple[np.ndarray, float]:
        """Positions (mm, shape (3,)) and the feed (mm/min) at time ``t``."""
        pos = self.pos_mm.copy()
        p = self.active()
        if p is None:
            return pos, 0.0
        x, v = p.at(t)
        pos[p.axis] = x
        return pos, abs(v) * 60.0

    @property
    def free(self) -> int:
        """Free planner blocks."""
        return self.blocks - len(self.queue) - len(self.held)

    def planned_mm(self, axis: int) -> float:
        """Where ``axis`` will rest once all planned (or held) motion is done."""
        for m in reversed(self.held):
            if m.axis == axis:
                return m.target_mm
        for p in reversed(self.queue):
            if p.axis == axis:
                return p.end_mm
        if self.stopping is not None and self.stopping.axis == axis:
            return self.stopping.end_mm
        return float(self.pos_mm[axis])

    def next_event_s(self) -> float | None:
        """Clock time at which the active profile ends, None when resting."""
        p = self.active()
        return None if p is None else p.t_end

    # ------------------------------------------------------------------ changes
    def plan(self, t: float, axis: int, kind: str, target_mm: float, feed_mm_min: float, accel_mm_s2: float) -> None:
        """Append a rest-to-rest move starting when everything before it ends."""
        ends = [t] + [p.t_end for p in self.queue[-1:]]
        if self.stopping is not None:
            ends.append(self.stopping.t_end)
        x0 = self.planned_mm(axis)
        self.queue.append(trapezoid(axis, kind, max(ends), x0, float(target_mm), feed_mm_min, accel_mm_s2))

    def freeze(self, t: float) -> None:
        """Stop everything abruptly at time ``t`` (reset, alarm, vanished port); flush queue and hold."""
        p = self.active()
        if p is not None:
            self.pos_mm[p.axis] = p.at(t)[0]
        self.queue.clear()
        self.stopping = None
        self.held.clear()
        self.hold = False

    def decelerate(self, t: float, accel_of: Callable[[int], float]) -> list[Profile]:
        """Replace the running motion by its controlled stop at ``t``; return the profiles cut short."""
        cut = list(self.queue)
        if self.queue:
            self.stopping = stop_from(self.queue[0], t, accel_of(self.queue[0].axis))
            self.queue.clear()
        return cut

    def feed_hold(self, t: float, accel_of: Callable[[int], float]) -> None:
        """Decelerate and keep the cut-short moves for :meth:`resume` (Hold:1, then Hold:0)."""
        cut = self.decelerate(t, accel_of)
        self.held = [HeldMove(p.axis, p.kind, p.end_mm, p.feed_mm_min) for p in cut] + self.held
        self.hold = True

    def resume(self, t: float, accel_of: Callable[[int], float]) -> bool:
        """Plan the held moves again once the hold is complete (a resume while still stopping is ignored)."""
        if not self.hold or self.stopping is not None:
            return False
        self.hold = False
        held, self.held = self.held, []
        for m in held:
            self.plan(t, m.axis, m.kind, m.target_mm, m.feed_mm_min, accel_of(m.axis))
        return True
