"""GRBL's ``$N`` settings over the simulated machine's named ones: the emulator's EEPROM.

Settings that mean something to the machine model (travel, rates,
acceleration, steps/mm, soft limits, homing) live in the simulated stage by
name (``hardware/machine_settings.py``); this table says which ``$N`` each
is. The rest (step pulse, status mask, inches, pin inversions, hard limits,
spindle...) only the firmware reads, so they live here.
"""
from __future__ import annotations

from collections.abc import Iterator, MutableMapping

from lps_gui.hardware.grbl.codes import SETTINGS, check_setting, stored_settings
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.stage import AXES

NAMED: dict[int, str] = {
    20: "soft_limits", 22: "homing", 24: "homing_locate_mm_min", 25: "homing_seek_mm_min", 27: "homing_pulloff_mm",
    **{100 + i: f"steps_per_mm.{a}" for i, a in enumerate(AXES)},
    **{110 + i: f"max_rate_mm_min.{a}" for i, a in enumerate(AXES)},
    **{120 + i: f"accel_mm_s2.{a}" for i, a in enumerate(AXES)},
    **{130 + i: f"travel_mm.{a}" for i, a in enumerate(AXES)},
}
FIRMWARE_ONLY_START = {23: 7.0}  # homing searches toward the low end on every axis (the stage's switch is there)


class GrblSettings(MutableMapping[int, float]):
    """``$N`` -> value: the machine's named settings read and written through, the firmware's own kept here.

    Item assignment stores as EEPROM does (``$RST``: no rules); :meth:`write` is ``$N=value`` with settings.c's
    checks (GRBL's error codes) and what it forces.
    """

    def __init__(self, stage: SimulatedStage) -> None:
        self.stage = stage
        self._own = {n: float(s.default) for n, s in SETTINGS.items() if n not in NAMED}
        self._own.update(FIRMWARE_ONLY_START)

    def __getitem__(self, number: int) -> float:
        key = NAMED.get(number)
        return self.stage.machine[key] if key is not None else self._own[number]

    def __setitem__(self, number: int, value: float) -> None:
        key = NAMED.get(number)
        if key is not None:
            self.stage.machine[key] = float(value)
        else:
            self._own[number] = float(value)

    def __delitem__(self, number: int) -> None:
        raise TypeError("GRBL settings cannot be removed")

    def __iter__(self) -> Iterator[int]:
        return iter(sorted({*self._own, *NAMED}))

    def __len__(self) -> int:
        return len(self._own) + len(NAMED)

    def write(self, number: int, value: float) -> None:
        """``$number=value``: GrblError as settings.c refuses it, else stored with what it forces ($22=0 clears $20)."""
        check_setting(self, number, value)
        for n, v in stored_settings(number, value).items():
            key = NAMED.get(n)
            if key is not None:
                self.stage.set_machine(key, v)
            else:
                self._own[n] = v
