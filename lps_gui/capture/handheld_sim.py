"""A simulated hand-held board for the guided intrinsics mode: an operator who holds every pose as asked.

The camera renders the board at :func:`goal_pose` of the current goal, with
a seeded jitter of position and tilt (a hand is not a fixture), so
``lps capture --intrinsics-views N`` on the simulated rig produces a set
that ``lps intrinsics`` calibrates, and the result can be checked against
the simulated camera's true intrinsics.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.render import BoardRenderer
from lps_gui.capture.intrinsics_plan import PoseGoal, goal_pose
from lps_gui.core.clock import Clock, RealClock
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.errors import HardwareError


class HandHeldBoardCamera(Camera):
    """:class:`Camera` whose frames show the board held at the goal ``goal_source()`` asks for.

    Parameters
    ----------
    board, intrinsics : the board and the simulated camera's true intrinsics.
    goal_source : returns the goal being asked for (e.g. ``IntrinsicsCapture.current``).
    jitter_mm, jitter_deg : sigma of the hand's position and tilt error.
    noise_grey, seed : image noise and the seed of every random draw.
    """

    def __init__(
        self,
        board: Board,
        intrinsics: CameraIntrinsics,
        goal_source: Callable[[], PoseGoal | None],
        jitter_mm: float = 5.0,
        jitter_deg: float = 3.0,
        noise_grey: float = 2.0,
        seed: int = 0,
        clock: Clock | None = None,
    ) -> None:
        self.board = board
        self.intrinsics = intrinsics
        self.goal_source = goal_source
        self.jitter_mm = float(jitter_mm)
        self.jitter_deg = float(jitter_deg)
        self.noise_grey = float(noise_grey)
        self.clock = clock or RealClock()
        self._rng = np.random.default_rng(seed)
        self._renderer: BoardRenderer | None = None

    def open(self) -> None:
        if self._renderer is None:
            self._renderer = BoardRenderer(self.board, self.intrinsics, noise_grey=self.noise_grey)

    @property
    def is_open(self) -> bool:
        return self._renderer is not None

    def close(self) -> None:
        self._renderer = None

    def grab(self) -> Frame:
        if self._renderer is None:
            raise HardwareError("simulated hand-held board: grab before open(); open the camera first")
        goal = self.goal_source()
        if goal is None:
            raise HardwareError("simulated hand-held board: no pose asked for; the plan is complete")
        R, t = goal_pose(goal, self.board, self.intrinsics)
        R = exp_so3(np.deg2rad(self._rng.normal(0.0, self.jitter_deg, size=3))) @ R
        t = t + self._rng.normal(0.0, self.jitter_mm, size=3)
        image = self._renderer.render(R, t, self._rng)
        return Frame(image=image, time=self.clock.now(), meta={"goal": goal.name})

    def properties(self) -> dict[str, Any]:
        w, h = self.intrinsics.image_size
        return {"driver": "HandHeldBoardCamera", "width": w, "height": h, "noise_grey": self.noise_grey}
