"""A capture plan as plain data: which targets, in which order, how often.

ISO 230-2 approaches every target from its own direction: a forward run
visits targets upward, a backward run downward, and the first target of a
run is reached from an overshoot so it too is approached from that side.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Iterator, NamedTuple

import numpy as np

from lps_gui.errors import InputError

DIRECTIONS = ("+", "-", "both")


def run_directions(directions: str) -> list[str]:
    """The passes of a run: "both" is forward then backward."""
    return ["+", "-"] if directions == "both" else [directions]


class PlannedStop(NamedTuple):
    """One frame to capture: its place in the session and its target."""

    index: int
    run: int
    direction: str  # "+" or "-"
    target_mm: float
    frame: int  # 0 .. frames_per_stop-1


@dataclass(frozen=True)
class Plan:
    """Targets from ``start_mm`` to ``stop_mm`` by ``step_mm``, or explicit ``targets_mm``."""

    start_mm: float = 0.0
    stop_mm: float = 10.0
    step_mm: float = 1.0
    targets_mm: tuple[float, ...] | None = None
    directions: str = "+"
    runs: int = 1
    overshoot_mm: float = 1.0
    settle_s: float = 0.2
    frames_per_stop: int = 1
    feed_mm_min: float = 600.0

    def __post_init__(self) -> None:
        if self.directions not in DIRECTIONS:
            raise InputError(f"plan: directions must be one of {DIRECTIONS}, got {self.directions!r}")
        from lps_gui.core.plan_limits import check_plan_fields

        check_plan_fields(self)  # counts and ranges before anything is built from them

    def targets(self) -> np.ndarray:
        """Ascending target positions (mm), shape (m,)."""
        if self.targets_mm is not None:
            return np.sort(np.asarray(self.targets_mm, dtype=float))
        n = int(round((self.stop_mm - self.start_mm) / self.step_mm)) + 1
        t = self.start_mm + self.step_mm * np.arange(n)
        return np.sort(t)

    def run_directions(self) -> list[str]:
        return run_directions(self.directions)

    def stops(self) -> Iterator[PlannedStop]:
        """Every frame of the session in capture order."""
        targets = self.targets()
        index = 0
        for run in range(1, self.runs + 1):
            for direction in self.run_directions():
                ordered = targets if direction == "+" else targets[::-1]
                for target in ordered:
                    for frame in range(self.frames_per_stop):
                        yield PlannedStop(index, run, direction, float(target), frame)
                        index += 1

    def n_frames(self) -> int:
        return len(self.targets()) * len(self.run_directions()) * self.runs * self.frames_per_stop

    def approach_start_mm(self, direction: str, first_target_mm: float) -> float:
        """Where to go before a run's first target so it is approached from ``direction``."""
        return first_target_mm - self.overshoot_mm if direction == "+" else first_target_mm + self.overshoot_mm

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        if d["targets_mm"] is not None:
            d["targets_mm"] = list(d["targets_mm"])
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Plan":
        known = {k: v for k, v in d.items() if k in cls.__dataclass_fields__}
        if known.get("targets_mm") is not None:
            if not isinstance(known["targets_mm"], (list, tuple)):
                raise InputError(f"plan: targets_mm must be a list of positions (mm), not {known['targets_mm']!r}")
            known["targets_mm"] = tuple(known["targets_mm"])
        try:
            return cls(**known)
        except TypeError as exc:
            raise InputError(f"plan: {exc}; see SPEC section 7 for the plan fields") from exc
