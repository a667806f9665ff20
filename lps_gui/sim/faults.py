"""Faults injected into a simulated capture at a known frame: the live checks' test bench.

One explicit hook (:class:`InjectedFaults`, the ``faults`` of a
:class:`~lps_gui.sim.rig.RigCamera`): the camera tells it the capture index
of each grab (its seeding call) and asks it for the camera pose and the
image of that frame. From the fault's frame on:

* ``"board_leaves_view"``: the camera shifted ``amount`` mm sideways (camera x), the board runs out of the image;
* ``"exposure"``: the image's grey levels times ``amount`` (light or gain changed);
* ``"bump"``: the camera turned ``amount`` mrad on its mount about its x axis (a knock, a loose screw);
* ``"jolt"``: that one frame only, the camera ``amount`` mm off across the motion (camera y): a view off the line.

The truth stays the stage's: what the estimator sees is a fault, not a stage error.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from lps_gui.core.geometry.rotation import exp_so3

KINDS = ("board_leaves_view", "exposure", "bump", "jolt")


@dataclass(frozen=True)
class Fault:
    kind: str
    at_index: int  # first capture index the fault is in
    amount: float  # mm, gain factor or mrad (see the module)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"fault kind {self.kind!r}: use one of {', '.join(KINDS)}")


class InjectedFaults:
    """The faults of one simulated capture, applied to the frames from their index on."""

    def __init__(self, faults: Sequence[Fault]) -> None:
        self.faults = tuple(faults)
        self._index = -1

    def at(self, index: int) -> None:
        """The next grab is capture ``index``."""
        self._index = int(index)

    def _active(self, kind: str) -> list[Fault]:
        return [f for f in self.faults if f.kind == kind and self._index >= f.at_index]

    def camera_pose(self, R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R_cam_board (K, 3, 3), t (K, 3)) as the moved camera sees the board."""
        for f in self._active("bump"):
            Rb = exp_so3(np.array([1e-3 * f.amount, 0.0, 0.0]))
            R, t = Rb @ R, t @ Rb.T
        for f in self._active("board_leaves_view"):
            t = t - np.array([f.amount, 0.0, 0.0])
        for f in self._active("jolt"):
            if self._index == f.at_index:
                t = t + np.array([0.0, f.amount, 0.0])
        return R, t

    def image(self, image: np.ndarray) -> np.ndarray:
        for f in self._active("exposure"):
            image = np.clip(np.rint(image.astype(np.float32) * f.amount), 0, 255).astype(image.dtype)
        return image
