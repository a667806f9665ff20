"""Live preview frames grabbed on a background thread.

``Camera.grab`` blocks until a frame exists and chessboard detection takes
tens of milliseconds, so both run on a plain worker thread that keeps only
the newest result; the GUI picks it up from a timer and never waits.
"""
from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from lps_gui.camera.base import Camera
from lps_gui.camera.detection import detect_chessboard, sharpness
from lps_gui.core.geometry.board import Board
from lps_gui.errors import LpsError
from lps_gui.gui.workers import one_line

log = logging.getLogger(__name__)

DETECT_HZ = 8.0  # board detection and focus figure at most this often; frames flow at the camera's rate


@dataclass(frozen=True)
class PreviewResult:
    """The newest frame with what was found in it."""

    number: int
    image: np.ndarray  # shape (H, W) or (H, W, 3), uint8
    corners_px: np.ndarray | None  # shape (N, 2) or None when no board was found
    sharpness: float | None  # higher is sharper; None when unavailable
    fps: float
    detection_available: bool


class PreviewGrabber:
    """Grab, detect and measure sharpness in a loop until :meth:`stop`.

    Parameters
    ----------
    camera : a camera, or a function returning one; opened on the preview thread
        (opening a device or building the simulated renderer takes a moment).
    board : returns the board to look for (the operator may change it live).
    max_fps : the loop never runs faster; below it, frames come at the camera's own rate.
    on_error : called once (from the worker thread) with a one-line message if grabbing fails.
    """

    def __init__(self, camera: Camera | Callable[[], Camera], board: Callable[[], Board], max_fps: float = 30.0,
                 on_error: Callable[[str], None] | None = None,
                 on_open: Callable[[Camera], None] | None = None) -> None:
        self._source = camera
        self.camera: Camera | None = None
        self.on_open = on_open
        self.board = board
        self.period_s = 1.0 / max_fps
        self.detect_period_s = 1.0 / DETECT_HZ
        self.on_error = on_error
        self._lock = threading.Lock()
        self._latest: PreviewResult | None = None
        self._stop = threading.Event()
        self._told = threading.Lock()  # held while a callback runs: once stop() returns, none runs (its receiver,
        # a panel, may be deleted then; a camera still opening after stop's join timed out used to emit into it)
        self._paused = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="camera-preview", daemon=True)
        self._detect = detect_chessboard
        self._sharpness = sharpness

    def start(self) -> "PreviewGrabber":
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the loop; no callback runs after this returns, even while the thread is still opening the camera
        (it then closes the camera it opened itself)."""
        with self._told:
            self._stop.set()
        self._thread.join(timeout_s)

    def _tell(self, callback: Callable[..., None] | None, *args: object) -> bool:
        """Call ``callback`` unless stopped; False when stopped (nothing called)."""
        with self._told:
            if self._stop.is_set():
                return False
            if callback is not None:
                callback(*args)
            return True

    def pause(self, on: bool) -> None:
        """Stop grabbing while someone else (the capture engine) owns the camera."""
        (self._paused.set if on else self._paused.clear)()

    def latest(self) -> PreviewResult | None:
        with self._lock:
            return self._latest

    def _open(self) -> bool:
        try:
            cam = self._source if isinstance(self._source, Camera) else self._source()
            if not cam.is_open:
                cam.open()
        except Exception as exc:  # no such device, busy, unplugged: one line to the operator
            _log_failure("camera not opened", exc)
            self._tell(self.on_error, one_line(exc))
            return False

        def opened(camera: Camera) -> None:
            self.camera = camera  # under the lock: stop() sees it set (the panel closes it) or the thread closes it
            if self.on_open:
                self.on_open(camera)

        if self._tell(opened, cam):
            return True
        if not isinstance(self._source, Camera):  # stopped while opening: nobody else holds what we opened
            cam.close()
        return False

    def _loop(self) -> None:
        if not self._open():
            return
        n = 0
        t_prev = time.monotonic()
        t_detect = -1e9
        corners = sharp = None  # the last detection, shown until the next one
        fps = 0.0
        while not self._stop.is_set():
            t0 = time.monotonic()
            if self._paused.is_set():
                self._stop.wait(self.period_s)
                continue
            try:
                frame = self.camera.grab()
            except Exception as exc:  # a vanished camera ends the preview, reported once
                _log_failure("camera preview stopped", exc)
                self._tell(self.on_error, one_line(exc))
                return
            image = frame.image
            if self._detect is not None and t0 - t_detect >= self.detect_period_s:
                t_detect = t0
                try:
                    corners = self._detect(image, self.board())
                    sharp = float(self._sharpness(image))
                except Exception:  # detection trouble must not stop the live picture
                    log.debug("preview detection failed", exc_info=True)
                    corners = sharp = None
            n += 1
            now = time.monotonic()
            dt = now - t_prev
            t_prev = now
            fps = 1.0 / dt if fps == 0.0 and dt > 0 else 0.8 * fps + 0.2 * (1.0 / max(dt, 1e-6))
            with self._lock:
                self._latest = PreviewResult(n, image, None if corners is None else np.asarray(corners),
                                             sharp, fps, self._detect is not None)
            self._stop.wait(max(0.0, self.period_s - (time.monotonic() - t0)))


def _log_failure(what: str, exc: BaseException) -> None:
    """An expected failure (an :class:`LpsError`: no such device...) is one line; the traceback only at DEBUG.

    The window reports the line to the operator (and logs it); a bug keeps its traceback in the log.
    """
    if isinstance(exc, LpsError):
        log.debug("%s: %s", what, one_line(exc), exc_info=exc)
    else:
        log.error("%s: %s", what, one_line(exc), exc_info=exc)
