"""The simulated camera on a stage it does not simulate: ``lps capture --stage grbl:PORT --camera sim``.

A user trying the GRBL emulator (``lps emulate-grbl``, or a board on a bench)
end to end without a camera: the rig's camera renders its board where the
stage *reports* the carriage, an ideal carriage (no straightness or angular
error: the stage's own errors are out of the simulator's sight). The truth
recorded beside each frame is that pose, so an estimate is checked against
what was rendered.
"""
from __future__ import annotations

import numpy as np

from lps_gui.core.stage_errors import TruePose
from lps_gui.hardware.stage import Stage
from lps_gui.sim.rig import RigCamera


def follow_reported_position(camera: RigCamera, stage: Stage) -> None:
    """Make ``camera`` render the board at ``stage``'s reported position (one axis)."""

    def pose() -> TruePose:
        return TruePose(axis_mm=np.array([float(stage.position_mm())]), straightness_um=np.zeros((1, 2)),
                        angles_urad=np.zeros((1, 3)))

    camera.pose_source = pose
