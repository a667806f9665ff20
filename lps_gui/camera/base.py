"""The Camera interface: open, grab a timestamped frame, properties, close."""
from __future__ import annotations

import abc
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

if TYPE_CHECKING:  # annotation only: the SDK cameras implement it
    from lps_gui.camera.control_surface import ControlSurface


@dataclass(frozen=True)
class Frame:
    """One grabbed image: 8-bit grey (H, W) or BGR (H, W, 3), with its time."""

    image: np.ndarray
    time: float  # seconds, the camera's clock (simulated or monotonic)
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def size(self) -> tuple[int, int]:
        h, w = self.image.shape[:2]
        return (w, h)


class Camera(abc.ABC):
    """A source of frames. ``grab`` blocks until a new frame is available.

    ``open`` sets ``_open``; sources that hold a device override ``close``
    and ``is_open`` to release and query it.
    """

    _open: bool = False
    pose_source: Callable[[], Any] | None = None  # a simulated camera: the stage's true pose it renders

    def property_device(self) -> Any:
        """The device whose properties (exposure, gain, focus, white balance) can be read and set, with
        ``get(prop)`` and ``set(prop, value)`` (``camera/controls.py``); None: the source has none."""
        return None

    @abc.abstractmethod
    def open(self) -> None: ...
    @abc.abstractmethod
    def grab(self) -> Frame: ...

    def close(self) -> None:
        self._open = False

    @property
    def is_open(self) -> bool:
        return self._open

    def properties(self) -> dict[str, Any]:
        """What a session.json records about this camera."""
        return {"driver": type(self).__name__}

    def control_surface(self) -> "ControlSurface | None":
        """The device's SDK controls (GenICam, pylon, gphoto2) while open; None: none, or OpenCV's (camera/controls.py)."""
        return None

    def __enter__(self) -> "Camera":
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
