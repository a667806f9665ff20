"""A preview stopped while its camera is still opening calls back nothing afterwards (the GUI suite's teardown
printed "RuntimeError: Signal source has been deleted" from the camera-preview thread under load)."""
from __future__ import annotations

import threading

import numpy as np

from lps_gui.camera.base import Frame
from lps_gui.core.geometry.board import Board
from lps_gui.gui.camera.preview import PreviewGrabber


class SlowCamera:
    """Opens only when the test says so; records whether it was closed."""

    def __init__(self, entered: threading.Event, release: threading.Event) -> None:
        self.entered, self.release = entered, release
        self.is_open = False
        self.closed = False

    def open(self) -> None:
        self.entered.set()
        assert self.release.wait(30.0)
        self.is_open = True

    def close(self) -> None:
        self.closed = True

    def grab(self):  # never reached: the grabber is stopped before the camera opens
        raise AssertionError("grabbed after stop")


def test_a_preview_stopped_while_opening_calls_nothing_and_closes_its_camera():
    entered, release = threading.Event(), threading.Event()
    cam = SlowCamera(entered, release)
    called: list[object] = []
    grabber = PreviewGrabber(lambda: cam, lambda: Board(4, 3, 10.0), on_open=called.append,
                             on_error=called.append).start()
    assert entered.wait(30.0)  # the thread is inside open()
    grabber.stop(timeout_s=0.0)  # the window closes: the join gives up at once, the panel is deleted next
    release.set()
    grabber._thread.join(30.0)
    assert not grabber._thread.is_alive()
    assert called == [] and cam.closed and grabber.camera is None


def test_a_preview_that_opened_still_reports_its_camera():
    class Quick:
        is_open = False

        def open(self) -> None:
            self.is_open = True

        def close(self) -> None:
            self.is_open = False

        def grab(self) -> Frame:
            return Frame(image=np.zeros((8, 8), np.uint8), time=0.0)

    opened = threading.Event()
    cams: list[object] = []
    grabber = PreviewGrabber(Quick, lambda: Board(4, 3, 10.0), on_open=lambda c: (cams.append(c), opened.set()))
    grabber.start()
    try:
        assert opened.wait(30.0) and cams == [grabber.camera]
    finally:
        grabber.stop()
