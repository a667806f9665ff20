"""The simulated rig driven through the registry's emulator: a real serial driver over a pty.

``lps capture --stage emulator --camera sim`` runs the driver an operator
uses on hardware (the registry's ``emulator`` kind names which: GRBL 1.1
today), against the emulator serving the rig's simulated stage, while the
simulated camera renders from that stage's true pose. This exercises the
whole real code path (commands, status polling, alarms) without hardware;
time runs ``time_scale`` times faster than real. The protocol is the
registry's business: this module names none.
"""
from __future__ import annotations

from typing import Any

from lps_gui.hardware.registry import kind_of
from lps_gui.hardware.stage import Stage
from lps_gui.sim.rig import RigStage

EMULATOR = "emulator"  # the registry's kind: a driver connected to an emulator serving a given simulated stage


def emulated_rig_stage(rig_stage: RigStage, time_scale: float = 1.0, faults: Any = None) -> Stage:
    """A connected driver talking to an emulator that serves ``rig_stage`` (seeded per capture)."""
    return kind_of(EMULATOR).build(EMULATOR, time_scale=time_scale, faults=faults, simulated=rig_stage)
