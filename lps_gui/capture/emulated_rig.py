"""The simulated rig driven through the GRBL emulator: the real serial driver over a pty.

``lps capture --stage emulator --camera sim`` runs the same GRBL 1.1 driver
an operator uses on hardware, against the emulator serving the rig's
simulated stage, while the simulated camera renders from that stage's true
pose. This exercises the whole real code path (G-code, status polling,
alarms) without hardware; time runs ``time_scale`` times faster than real.
"""
from __future__ import annotations

from typing import Any

from lps_gui.capture.simulated_rig import RigStage
from lps_gui.hardware.stage import Stage


def emulated_rig_stage(rig_stage: RigStage, time_scale: float = 1.0, faults: Any = None) -> Stage:
    """A connected GRBL driver talking to an emulator that serves ``rig_stage``.

    The returned stage forwards the capture engine's ``seed_capture`` hook to
    the rig's stage and stops the emulator when it disconnects.
    """
    from lps_gui.hardware.grbl.driver import GrblStage
    from lps_gui.hardware.grbl.emulator import GrblEmulator

    emu = GrblEmulator(rig_stage, faults=faults, time_scale=time_scale)
    path = emu.start()

    class EmulatedRigStage(GrblStage):
        emulator = emu
        simulated = rig_stage

        def seed_capture(self, key: int) -> None:
            rig_stage.seed_capture(key)

        def disconnect(self) -> None:
            try:
                super().disconnect()
            finally:
                emu.stop()

        def describe(self) -> dict:
            return {**super().describe(), "emulated": rig_stage.describe()}

    stage = EmulatedRigStage(path)
    try:
        stage.connect()
    except BaseException:
        emu.stop()
        raise
    return stage
