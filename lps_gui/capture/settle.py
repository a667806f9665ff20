"""Settle detection and frame averaging at a stop: the frame is taken once the picture stopped moving.

A stage rings after a move (a decaying oscillation of the carriage, the
camera arm or the board stand); a fixed settle time is either too long or
too short. Here the camera itself is the sensor: frames are grabbed until
consecutive ones show the board at the same place, within ``settle_px``
(the mean corner displacement: vibration moves the board rigidly in the
image, and the mean over N corners has 1/sqrt(N) of one corner's noise), or
until ``timeout_s`` (then the last frame is taken and the record says how
long it waited). ``agree_frames`` consecutive frames must agree pairwise:
2 is the plain "two consecutive frames agree"; the default 3 (two pairs in
a row) is not fooled by the turning point of an oscillation, where one pair
of frames sampled either side of a peak agrees by chance. ``average`` frames are then grabbed and averaged pixel by
pixel: the corners found in the mean image are the mean of the corners to
first order (sub-pixel refinement is linear in the grey levels for small
noise), so their noise falls as 1/sqrt(N).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.detection import detect_chessboard
from lps_gui.core.clock import Clock
from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError

MAX_GRABS = 500  # a camera whose clock does not advance must not loop forever


@dataclass(frozen=True)
class SettleOptions:
    """``settle_px`` None: no settle detection; ``average`` frames averaged into each stored frame."""

    settle_px: float | None = None
    timeout_s: float = 10.0
    average: int = 1
    agree_frames: int = 3

    def __post_init__(self) -> None:
        if self.settle_px is not None and not self.settle_px > 0:
            raise InputError(f"--settle-px {self.settle_px}: give a positive shift in pixels, e.g. 0.05")
        if not self.timeout_s > 0:
            raise InputError(f"--settle-timeout-s {self.timeout_s}: give a positive time in seconds")
        if not 2 <= int(self.agree_frames) <= 100:
            raise InputError(f"--settle-frames {self.agree_frames}: give a whole number from 2 to 100")
        if not 1 <= int(self.average) <= 1000:
            raise InputError(f"--average-frames {self.average}: give a whole number from 1 to 1000")

    @property
    def active(self) -> bool:
        return self.settle_px is not None or self.average > 1

    def to_dict(self) -> dict[str, Any]:
        """What session.json records under ``acquisition``."""
        out: dict[str, Any] = {"average_frames": int(self.average)}
        if self.settle_px is not None:
            out.update(settle_px=float(self.settle_px), settle_timeout_s=float(self.timeout_s),
                       settle_frames=int(self.agree_frames))
        return out


@dataclass(frozen=True)
class StopFrame:
    """The frame to store for a stop, with how it was obtained."""

    frame: Frame
    grabbed: list[Frame] = field(default_factory=list)  # every frame averaged into it (checked for locked controls)
    settle_s: float | None = None  # time from the first settle grab to the frame that agreed; None: not settled here
    settled: bool = True
    shift_px: float | None = None


def board_shift_px(a_px: np.ndarray, b_px: np.ndarray) -> float:
    """Length of the mean corner displacement between two detections of one board (px)."""
    return float(np.linalg.norm(np.mean(np.asarray(b_px, float) - np.asarray(a_px, float), axis=0)))


def average_frames(frames: list[Frame]) -> Frame:
    """The pixel mean of ``frames`` (8-bit, rounded), with the time and meta of the last."""
    if len(frames) == 1:
        return frames[0]
    mean = np.mean(np.stack([f.image.astype(np.float32) for f in frames]), axis=0)
    last = frames[-1]
    return Frame(image=np.clip(np.rint(mean), 0, 255).astype(np.uint8), time=last.time, meta={**last.meta, "averaged": len(frames)})


class Settler:
    """Grabs a stop's frame from ``camera``: settled (when asked) then averaged."""

    def __init__(self, board: Board, options: SettleOptions, clock: Clock) -> None:
        self.board, self.options, self.clock = board, options, clock

    def _corners(self, frame: Frame, reference: np.ndarray | None) -> np.ndarray | None:
        return detect_chessboard(frame.image, self.board, reference_px=reference)

    def settle(self, camera: Camera) -> tuple[Frame, float, bool, float | None]:
        """Grab until ``agree_frames`` consecutive frames agree; (last frame, settle time, agreed, last shift)."""
        t0 = self.clock.now()
        frame = camera.grab()
        prev_c = self._corners(frame, None)
        shift: float | None = None
        agreeing = 1  # frames in a row whose consecutive shifts are under the threshold
        for _ in range(MAX_GRABS):
            frame = camera.grab()
            corners = self._corners(frame, prev_c)
            if corners is not None and prev_c is not None and len(corners) == len(prev_c):
                shift = board_shift_px(prev_c, corners)
                agreeing = agreeing + 1 if shift < float(self.options.settle_px or 0.0) else 1
                if agreeing >= self.options.agree_frames:
                    return frame, self.clock.now() - t0, True, shift
            else:
                agreeing = 1
            if self.clock.now() - t0 >= self.options.timeout_s:
                break
            prev_c = corners
        return frame, self.clock.now() - t0, False, shift

    def grab(self, camera: Camera, settle: bool) -> StopFrame:
        """The stop's frame: settled first when ``settle`` (the first frame of a stop) and options ask it."""
        settle_s, settled, shift = None, True, None
        if settle and self.options.settle_px is not None:
            first, settle_s, settled, shift = self.settle(camera)
        else:
            first = camera.grab()
        grabbed = [first] + [camera.grab() for _ in range(int(self.options.average) - 1)]
        return StopFrame(average_frames(grabbed), grabbed, settle_s, settled, shift)
