"""The simulated rig driven through the GRBL emulator: the real serial driver over a pty.

``lps capture --stage emulator --camera sim`` runs the same GRBL 1.1 driver
an operator uses on hardware, against the emulator serving the rig's
simulated stage, while the simulated camera renders from that stage's true
pose. This exercises the whole real code path (G-code, status polling,
alarms) without hardware; time runs ``time_scale`` times faster than real.
"""
from __future__ import annotations

from typing import Any

from lps_gui.hardware.grbl.emulator import emulated_grbl_stage
from lps_gui.hardware.stage import Stage
from lps_gui.sim.rig import RigStage


def emulated_rig_stage(rig_stage: RigStage, time_scale: float = 1.0, faults: Any = None) -> Stage:
    """A connected GRBL driver talking to an emulator that serves ``rig_stage`` (seeded per capture)."""
    return emulated_grbl_stage(time_scale=time_scale, faults=faults, simulated=rig_stage)
