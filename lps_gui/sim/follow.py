"""The simulated rig riding any stage: ``lps capture --stage marlin:PORT --camera sim`` (or manual, command...).

The operator's stage (a driver, perhaps talking to an emulator in another
process) is driven as always; after each of its moves ends, the simulated
rig's stage is moved to the position the driver *reports* (queued moves before
the last one: where they were commanded), so the simulated camera renders the
board where the rig's error model puts the carriage there: a driver that
misreads its position shows in the estimate. The rig's draws are seeded per stop as on ``--stage sim``, so the
session's estimate equals the simulated stage's for the same seed: a test of
the driver's whole path (protocol, waits, errors, resume) against the truth.
"""
from __future__ import annotations

from lps_gui.hardware.stage import AXES, Stage, StageStatus


class FollowedStage(Stage):
    """``driver`` moves; ``simulated`` (the rig's stage) follows every completed move on its own clock."""

    def __init__(self, driver: Stage, rig_stage: Stage) -> None:
        super().__init__()
        self.driver = driver
        self.simulated = rig_stage
        self.clock = rig_stage.clock
        self.axis = driver.axis
        self.travel_mm = driver.travel_mm
        self.axis_travel_mm = driver.axis_travel_mm
        self.events = driver.events
        self._pending: list[tuple[float, float, str | None]] = []

    def connect(self) -> None:
        self.driver.connect()

    def disconnect(self) -> None:
        try:
            self.driver.disconnect()
        finally:
            self.simulated.disconnect()

    @property
    def connected(self) -> bool:
        return self.driver.connected

    def status(self) -> StageStatus:
        return self.driver.status()

    def home(self) -> None:
        self.driver.home()

    def move_to(self, position_mm: float, feed_mm_min: float, axis: str | None = None) -> None:
        self.driver.move_to(position_mm, feed_mm_min, axis)
        self._pending.append((position_mm, feed_mm_min, axis))

    def wait_idle(self, timeout_s: float = 60.0) -> StageStatus:
        st = self.driver.wait_idle(timeout_s)
        pending, self._pending = self._pending, []
        for k, (position_mm, feed_mm_min, axis) in enumerate(pending):
            name = axis or self.driver.axis
            last = all((a or self.driver.axis) != name for _, _, a in pending[k + 1:])
            self.simulated.move_to(st.work_mm[AXES.index(name)] if last else position_mm, feed_mm_min, axis)
        self.simulated.wait_idle(timeout_s=3600.0)
        return st

    def stop(self) -> None:
        self.driver.stop()

    def true_pose(self):
        return self.simulated.true_pose()

    def describe(self) -> dict:
        return {**self.driver.describe(), "followed_by": "simulated rig"}
