"""A camera through OpenCV's VideoCapture: a device index, a video or image-sequence file, or a stream URL.

Frames are stored 8-bit grey by default: chessboard detection works on grey
and a grey PNG takes a third of the disk of a colour one; pass ``grey=False``
to keep OpenCV's BGR.
"""
from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import HardwareError


class OpenCVCamera(Camera):
    """:class:`Camera` over ``cv2.VideoCapture``.

    Parameters
    ----------
    source : device index (0, 1...), a file (video, or an image sequence
        such as ``img_%04d.png``) or a URL (``rtsp://...``, ``http://...``).
    width, height, fps : requested capture format (devices only; the device
        may choose another, :meth:`properties` says what it delivers).
    grey : convert frames to 8-bit grey (H, W).
    clock : timestamps frames (monotonic real time by default).
    """

    backend: int = cv2.CAP_ANY  # OpenCV's videoio back end (V4L2Camera: cv2.CAP_V4L2)
    device_controls: bool | None = None  # None: a device index has controls, files and URLs do not

    def __init__(
        self,
        source: int | str,
        width: int | None = None,
        height: int | None = None,
        fps: float | None = None,
        grey: bool = True,
        clock: Clock | None = None,
    ) -> None:
        self.source = source
        self.requested = {"width": width, "height": height, "fps": fps}
        self.grey = grey
        self.clock = clock or RealClock()
        self._cap: cv2.VideoCapture | None = None
        self._frame_no = 0

    @property
    def is_device(self) -> bool:
        """A device (index or V4L2 node) with controls, not a file or a stream."""
        return isinstance(self.source, int) if self.device_controls is None else self.device_controls

    @property
    def _name(self) -> str:
        return f"camera {self.source!r}" if isinstance(self.source, str) else f"camera device {self.source}"

    def open(self) -> None:
        if self._cap is not None:
            return
        cap = cv2.VideoCapture(self.source, self.backend)
        if not cap.isOpened():
            cap.release()
            hint = (
                "check the index, the cable and that no other program uses it"
                if self.is_device
                else "check the path or URL and that OpenCV can decode it"
            )
            raise HardwareError(f"{self._name}: cannot open; {hint}")
        props = {"width": cv2.CAP_PROP_FRAME_WIDTH, "height": cv2.CAP_PROP_FRAME_HEIGHT, "fps": cv2.CAP_PROP_FPS}
        for key, prop in props.items():
            if self.requested[key]:
                cap.set(prop, float(self.requested[key]))
        self._cap = cap
        self._frame_no = 0

    @property
    def is_open(self) -> bool:
        return self._cap is not None

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None

    def property_device(self) -> Any:
        """The open ``cv2.VideoCapture`` of a device; None while closed and for files and streams (no controls)."""
        return self._cap if self.is_device else None

    def grab(self) -> Frame:
        """The next frame; HardwareError when the device fails or a file has no more frames."""
        if self._cap is None:
            raise HardwareError(f"{self._name}: grab before open(); open the camera first")
        ok, image = self._cap.read()
        if not ok or image is None:
            if self.is_device or "://" in str(self.source):
                raise HardwareError(f"{self._name}: no frame delivered; check the cable or stream, then resume")
            raise HardwareError(f"{self._name}: no more frames after {self._frame_no}; the file is exhausted")
        image = _to_8bit(image, self.grey)
        self._frame_no += 1
        meta = {"frame": self._frame_no, "pos_msec": float(self._cap.get(cv2.CAP_PROP_POS_MSEC))}
        return Frame(image=image, time=self.clock.now(), meta=meta)

    def properties(self) -> dict[str, Any]:
        out: dict[str, Any] = {"driver": "OpenCVCamera", "source": self.source, "grey": self.grey, "channels": 1 if self.grey else 3}
        if self._cap is not None:
            out.update(
                width=int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
                height=int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT)),
                fps=float(self._cap.get(cv2.CAP_PROP_FPS)),
                backend=self._cap.getBackendName(),
            )
        return out


def _to_8bit(image: np.ndarray, grey: bool) -> np.ndarray:
    """8-bit grey (H, W) or BGR (H, W, 3) from whatever the decoder gave."""
    if image.dtype != np.uint8:
        scale = 255.0 / 65535.0 if image.dtype == np.uint16 else 1.0
        image = np.clip(image.astype(np.float32) * scale, 0, 255).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    if grey and image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if not grey and image.ndim == 2:
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    return image
