"""What the SDK cameras share: the device handle, closing it whatever state it is in, the frame they build.

Two ways to grab: by default every :meth:`grab` is a fresh acquisition (it
starts after the call, so a capture never stores a frame exposed during the
move, whatever the SDK buffered); :meth:`set_streaming` (the GUI preview) lets
the device run at its own rate and hands out the newest frame.
"""
from __future__ import annotations

import threading
from typing import Any

import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.control_surface import ControlSurface
from lps_gui.camera.pixels import BayerGrey, to_grey8
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import HardwareError


class SdkCamera(Camera):
    """A :class:`Camera` over one SDK device handle (``_handle``, None while closed) and its control surface."""

    driver = "SdkCamera"

    def __init__(self, source: str, clock: Clock | None = None) -> None:
        self.source = source
        self.clock = clock or RealClock()
        self._handle: Any = None
        self._controls: ControlSurface | None = None
        self._bayer = BayerGrey()  # gains fixed at the first raw frame
        self._frame_no = 0
        self.streaming = False
        self._grab_lock = threading.Lock()  # the preview thread grabs while the GUI switches the mode

    def set_streaming(self, on: bool) -> None:
        """Run the device continuously (preview at the device's rate) or grab fresh frames one by one (capture)."""
        with self._grab_lock:
            if self.streaming and not on and self._handle is not None:
                try:
                    self._stop_stream(self._handle)
                except Exception:  # a vanished device is not streaming any more either
                    pass
            self.streaming = bool(on)

    def _stop_stream(self, handle: Any) -> None:
        """Stop a continuous acquisition (SDKs that stream override it)."""

    @property
    def is_open(self) -> bool:
        return self._handle is not None

    def _release(self, handle: Any) -> None:
        """Let the SDK free the device (may raise: the device may be gone)."""

    def close(self) -> None:
        handle, self._handle, self._controls = self._handle, None, None
        if handle is not None:
            try:
                self._release(handle)
            except Exception:  # a vanished device cannot be released: it is gone either way
                pass

    def control_surface(self) -> ControlSurface | None:
        return self._controls

    def _opened(self) -> Any:
        if self._handle is None:
            raise HardwareError(f"camera {self.source}: not open; open the camera first")
        return self._handle

    def _frame(self, image: np.ndarray, pixel_format: str | None = None, **meta: Any) -> Frame:
        """The grabbed frame (raw data converted when ``pixel_format`` is given), with the controls in force."""
        if pixel_format is not None:
            image = to_grey8(image, pixel_format, self._bayer)
            meta["pixel_format"] = pixel_format
        self._frame_no += 1
        if self._controls is not None:
            meta["controls"] = self._controls.frame_values()
        return Frame(image=image, time=self.clock.now(), meta={"frame": self._frame_no, **meta})

    @property
    def bayer_gains(self) -> list[list[float]] | None:
        """The raw mosaic's sub-lattice gains (2x2) once fixed by a first Bayer frame; None before."""
        return None if self._bayer.gains is None else self._bayer.gains.astype(float).tolist()  # exact: a resume reuses them

    def set_bayer_gains(self, gains: Any) -> None:
        """Fix the gains (a resumed capture: those of its first frames, not ones estimated from another frame)."""
        self._bayer = BayerGrey(np.asarray(gains, dtype=np.float64))

    def properties(self) -> dict[str, Any]:
        out: dict[str, Any] = {"driver": self.driver, "source": self.source, "channels": 1}
        if self._controls is not None:
            out["controls"] = self._controls.values()
        if self._bayer.gains is not None:
            out["bayer_gains"] = self.bayer_gains
        return out
