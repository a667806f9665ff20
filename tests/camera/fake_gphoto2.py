"""A stand-in for the ``gphoto2`` module with the real one's call surface, replaying a recorded sequence.

The calls and results follow a run of python-gphoto2 2.6.4 (libgphoto2
2.5.34) on the library's virtual camera: ``capture`` answers a CameraFilePath
(folder /store_00010001/DCIM/100GPHOT, first name GPH_0099.JPG), ``file_get`` a
CameraFile whose ``get_data_and_size`` is the picture's bytes, ``file_delete``
nothing. Here the pictures are the simulated camera's renders (PNG, so the
comparison is exact); ``unplug_at`` makes the n-th call of a kind raise
GP_ERROR_IO_USB_FIND (-52) like a camera unplugged at that moment.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Callable

import cv2

GP_CAPTURE_IMAGE = 0
GP_FILE_TYPE_NORMAL = 1
GP_ERROR_MODEL_NOT_FOUND = -105
GP_ERROR_UNKNOWN_PORT = -5
GP_ERROR_IO_USB_FIND = -52
FOLDER = "/store_00010001/DCIM/100GPHOT"


class GPhoto2Error(Exception):
    def __init__(self, code: int) -> None:
        self.code = code
        super().__init__(f"[{code}] {'Could not find the requested device on the USB port' if code == -52 else 'Unknown model'}")


class Widget:
    def __init__(self, value: str, choices: tuple[str, ...]) -> None:
        self.value, self.choices = value, choices

    def get_value(self) -> str:
        return self.value

    def set_value(self, v: str) -> None:
        if v not in self.choices:
            raise GPhoto2Error(-2)
        self.value = v

    def count_choices(self) -> int:
        return len(self.choices)

    def get_choice(self, i: int) -> str:
        return self.choices[i]


class Config:
    def __init__(self, widgets: dict[str, Widget]) -> None:
        self.widgets = widgets

    def get_child_by_name(self, name: str) -> Widget:
        if name not in self.widgets:
            raise GPhoto2Error(-2)
        return self.widgets[name]


class FakeGPhoto2:
    """The module: ``Camera()`` gives a camera over ``pictures`` (a callable rendering the next picture)."""

    GP_CAPTURE_IMAGE, GP_FILE_TYPE_NORMAL = GP_CAPTURE_IMAGE, GP_FILE_TYPE_NORMAL
    GP_ERROR_MODEL_NOT_FOUND, GP_ERROR_UNKNOWN_PORT = GP_ERROR_MODEL_NOT_FOUND, GP_ERROR_UNKNOWN_PORT
    GPhoto2Error = GPhoto2Error

    def __init__(self, pictures: Callable[[], Any]) -> None:
        self.pictures = pictures
        self.calls: list[tuple] = []
        self.unplug_at: dict[str, int] = {}  # call kind -> the n-th such call (1-based) fails
        self.counts: dict[str, int] = {}
        self.plugged = True
        self.config = Config({"shutterspeed": Widget("1/125", ("1/60", "1/125", "1/250")),
                              "iso": Widget("100", ("Auto", "100", "200")),
                              "imageformat": Widget("Large Fine JPEG", ("Large Fine JPEG", "RAW")),
                              "whitebalance": Widget("Automatic", ("Automatic", "Daylight", "Tungsten"))})
        self._next = 98  # the virtual camera named its first picture GPH_0099.JPG
        module = self

        class Camera:
            def __getattr__(self, name: str) -> Any:
                return module._call(name)

        class _List:
            def count(self) -> int:
                return 1 if module.plugged else 0

            def get_name(self, i: int) -> str:
                return "Nikon DSC D750"

            def get_value(self, i: int) -> str:
                return "usb:001,001"

        Camera.autodetect = staticmethod(lambda: _List())
        self.Camera = Camera

    def _call(self, name: str) -> Callable[..., Any]:
        def call(*args: Any) -> Any:
            self.calls.append((name,) + args)
            n = self.counts[name] = self.counts.get(name, 0) + 1
            if self.unplug_at.get(name) == n:
                self.plugged = False
            if not self.plugged and name != "exit":
                raise GPhoto2Error(GP_ERROR_IO_USB_FIND)
            return getattr(self, "_" + name)(*args)
        return call

    def _init(self) -> None:
        pass

    def _exit(self) -> None:
        pass

    def _get_config(self) -> Config:
        return self.config

    def _set_config(self, config: Config) -> None:
        pass

    def _capture(self, kind: int) -> SimpleNamespace:
        assert kind == GP_CAPTURE_IMAGE
        self._next += 1
        self._picture = cv2.imencode(".png", self.pictures())[1].tobytes()
        return SimpleNamespace(folder=FOLDER, name=f"GPH_{self._next:04d}.JPG")

    def _file_get(self, folder: str, name: str, kind: int) -> SimpleNamespace:
        assert (folder, kind) == (FOLDER, GP_FILE_TYPE_NORMAL)
        return SimpleNamespace(get_data_and_size=lambda: memoryview(self._picture))

    def _file_delete(self, folder: str, name: str) -> None:
        pass

    def replug(self) -> None:
        self.plugged = True
        self.unplug_at.clear()
