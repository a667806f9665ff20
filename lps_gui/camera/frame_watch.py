"""Warn when the picture's brightness or sharpness jumps between frames: an auto exposure or autofocus at work.

With the stage at rest (or moving a little) the mean grey level and the
Laplacian sharpness of consecutive frames change slowly; a step of several per
cent in brightness or tens of per cent in sharpness means the camera changed
its exposure or focus on its own, which moves the detected corners and spoils
the measurement. The check is two numbers per frame (numpy and one OpenCV call).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

BRIGHTNESS_JUMP = 0.08  # relative change of the mean grey level between frames
SHARPNESS_JUMP = 0.35  # relative change of the Laplacian variance


def brightness(image: np.ndarray) -> float:
    return float(np.mean(image))


def sharpness(image: np.ndarray) -> float:
    """Variance of the Laplacian (the focus figure of the camera panel)."""
    import cv2

    grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return float(cv2.Laplacian(grey, cv2.CV_64F).var())


@dataclass
class FrameWatch:
    """Feed frames (or their figures); :meth:`check` returns a one-line warning on a jump, else None."""

    brightness_jump: float = BRIGHTNESS_JUMP
    sharpness_jump: float = SHARPNESS_JUMP
    _last: tuple[float, float] | None = field(default=None, init=False)

    def reset(self) -> None:
        self._last = None

    def check(self, image: np.ndarray, sharp: float | None = None) -> str | None:
        """``sharp``: the frame's sharpness if already known (negative: unknown, not checked)."""
        b = brightness(image)
        s = sharpness(image) if sharp is None else float(sharp)
        last, self._last = self._last, (b, s)
        if last is None:
            return None
        (b0, s0) = last
        if b0 > 1.0 and abs(b - b0) / b0 > self.brightness_jump:
            return (f"brightness jumped {100 * (b - b0) / b0:+.0f}% between frames: auto exposure or gain at work? "
                    "Fix the exposure before measuring")
        if s0 > 1.0 and s >= 0 and abs(s - s0) / s0 > self.sharpness_jump:
            return (f"sharpness jumped {100 * (s - s0) / s0:+.0f}% between frames: autofocus at work? "
                    "Fix the focus before measuring")
        return None
