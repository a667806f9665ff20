"""The simulated machine's settings by name (travel, rates, acceleration, resolution, homing), no protocol's numbers.

The simulated stage keeps these and offers them through the ``Settings``
capability (numbered by their place in :data:`MACHINE_SETTINGS`, labelled by
key); a protocol's emulator maps its own numbering onto the keys
(``hardware/grbl/settings.py``: ``$110`` is ``max_rate_mm_min.X``), so the
machine model never learns a controller's numbers.
"""
from __future__ import annotations

from typing import NamedTuple

from lps_gui.hardware.stage import AXES


class NamedSetting(NamedTuple):
    """One setting of the machine model: its key, name, unit and meaning; ``flag``: 0 or 1 only."""

    key: str
    name: str
    unit: str
    description: str
    flag: bool = False


def _per_axis(key: str, name: str, unit: str, description: str) -> list[NamedSetting]:
    return [NamedSetting(f"{key}.{a}", f"{a} {name}", unit, f"{a} axis: {description}") for a in AXES]


MACHINE_SETTINGS: tuple[NamedSetting, ...] = (
    NamedSetting("soft_limits", "soft limits", "boolean", "a move whose target is outside the travel raises an alarm",
                 flag=True),
    NamedSetting("homing", "homing cycle", "boolean", "homing to the low limit switch is enabled", flag=True),
    NamedSetting("homing_locate_mm_min", "homing locate feed", "mm/min", "slow feed that locates the switch"),
    NamedSetting("homing_seek_mm_min", "homing seek rate", "mm/min", "fast feed that finds the switch"),
    NamedSetting("homing_pulloff_mm", "homing pull-off", "mm", "distance homing retreats from the switch"),
    *_per_axis("steps_per_mm", "steps per mm", "step/mm", "motor steps per millimetre"),
    *_per_axis("max_rate_mm_min", "maximum rate", "mm/min", "the fastest feed (rapid moves use it)"),
    *_per_axis("accel_mm_s2", "acceleration", "mm/s^2", "the acceleration of every move"),
    *_per_axis("travel_mm", "travel", "mm", "span of the soft-limit range above its low end"),
)
BY_KEY: dict[str, NamedSetting] = {s.key: s for s in MACHINE_SETTINGS}
NUMBER: dict[str, int] = {s.key: i + 1 for i, s in enumerate(MACHINE_SETTINGS)}  # the Settings capability's numbers
KEY: dict[int, str] = {n: k for k, n in NUMBER.items()}


def machine_defaults(max_rate_mm_min: float, accel_mm_s2: float, travel: list[tuple[float, float]],
                     soft_limits: bool) -> dict[str, float]:
    """The simulated stage's settings at start: its rates and travel, homing on (seek at the max rate, locate
    at 100 mm/min, 1 mm pull-off), 250 steps/mm."""
    values = {"soft_limits": float(soft_limits), "homing": 1.0, "homing_locate_mm_min": 100.0,
              "homing_seek_mm_min": float(max_rate_mm_min), "homing_pulloff_mm": 1.0}
    for a, (lo, hi) in zip(AXES, travel):
        values.update({f"steps_per_mm.{a}": 250.0, f"max_rate_mm_min.{a}": float(max_rate_mm_min),
                       f"accel_mm_s2.{a}": float(accel_mm_s2), f"travel_mm.{a}": hi - lo})
    return values


def travel_text(values: dict[str, float]) -> str:
    """The soft-limit travel of each axis and whether soft limits are on, from the named settings."""
    spans = [f"{a} {values[f'travel_mm.{a}']:g} mm" for a in AXES if f"travel_mm.{a}" in values]
    if not spans:
        return "travel: unknown"
    limits = "soft limits ON" if values.get("soft_limits") else "soft limits off: nothing stops a move past the ends"
    return f"travel {', '.join(spans)}; {limits}"
