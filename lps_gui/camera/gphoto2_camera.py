"""A tethered DSLR or mirrorless camera through python-gphoto2 (``gphoto2:`` first camera, ``gphoto2:PORT``).

Each grab is the library's own sequence: ``capture`` (the camera exposes and
stores the picture), ``file_get`` (download), ``file_delete`` (free the card),
then decode. A camera unplugged or switched off mid-capture raises a gphoto2
error at one of these calls: the adapter exits the camera and reports one
line; the capture engine pauses with nothing listed for that frame and its
next ``run`` reopens the camera and retakes it. Controls are the camera's
config widgets: ``shutterspeed`` (exposure), ``iso`` (gain), ``imageformat``
(pixel format), ``whitebalance``; ISO and white balance must not be
automatic during a capture. Pictures come as JPEG (lossy in the camera: use
its finest quality) or TIFF; raw files (NEF, CR2...) are refused.
"""
from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from lps_gui.camera.base import Frame
from lps_gui.camera.control_surface import ControlSurface, Value
from lps_gui.camera.extras import first_line, gphoto2_sdk
from lps_gui.camera.pixels import colour_to_grey, to_8bit
from lps_gui.camera.sdk_device import SdkCamera
from lps_gui.core.clock import Clock
from lps_gui.core.image_header import HEADER_BYTES, bytes_reader, check_image_header
from lps_gui.errors import HardwareError, InputError
from lps_gui.quiet_decode import imdecode_quiet

WIDGETS = {"exposure": "shutterspeed", "gain": "iso", "pixel format": "imageformat", "white balance": "whitebalance"}
AUTO_WORDS = ("auto", "automatic")
FIXED_WHITE_BALANCE = ("Daylight", "daylight", "Sunny")


def list_gphoto2_devices() -> list[tuple[str, str]]:
    """(label, source) of the cameras libgphoto2 detects."""
    gp = gphoto2_sdk("gphoto2:")
    found = gp.Camera.autodetect()
    return [(f"{found.get_name(i)} ({found.get_value(i)})", f"gphoto2:{found.get_value(i)}") for i in range(found.count())]


class GPhoto2Controls(ControlSurface):
    """The config widgets of a gphoto2 camera (values are the camera's strings, e.g. "1/125", "100")."""

    def __init__(self, camera: Any) -> None:
        self.camera = camera

    def _widgets(self) -> dict[str, Any]:
        config = self.camera.get_config()
        out = {}
        for name, widget in WIDGETS.items():
            try:
                out[name] = config.get_child_by_name(widget)
            except Exception:  # the camera has no such setting
                continue
        self._config = config
        return out

    def values(self) -> dict[str, Value]:
        return {name: str(w.get_value()) for name, w in self._widgets().items()}

    def choices(self, name: str) -> tuple[str, ...] | None:
        w = self._widgets().get(name)
        if w is None:
            return None
        return tuple(str(w.get_choice(i)) for i in range(w.count_choices()))

    def set(self, name: str, value: Value) -> bool:
        w = self._widgets().get(name)
        if w is None:
            return False
        try:
            w.set_value(str(value))
            self.camera.set_config(self._config)
        except Exception:  # a value the camera does not offer, or a read-only setting
            return False
        return True

    def autos(self) -> dict[str, bool]:
        return {name: str(v).lower() in AUTO_WORDS for name, v in self.values().items() if name in ("gain", "white balance")}

    def set_auto(self, name: str, on: bool) -> bool:
        if name != "white balance" or on:
            return False
        offered = self.choices(name) or ()
        fixed = next((c for c in FIXED_WHITE_BALANCE if c in offered), None)
        return fixed is not None and self.set(name, fixed)

    def lock(self) -> dict[str, Value]:
        locked = super().lock()
        still_auto = [n for n, on in self.autos().items() if on]
        if still_auto:
            raise InputError(f"camera gphoto2: {' and '.join(still_auto)} is automatic; set a fixed value on the camera "
                             "(mode dial M, fixed ISO), then start the capture")
        return locked


class GPhoto2Camera(SdkCamera):
    """:class:`Camera` over ``gphoto2.Camera``: capture, download, delete, decode to 8-bit grey."""

    driver = "GPhoto2Camera"

    def __init__(self, port: str = "", clock: Clock | None = None) -> None:
        super().__init__(f"gphoto2:{port}", clock)
        self.port = port

    def open(self) -> None:
        if self._handle is not None:
            return
        gp = gphoto2_sdk(self.source)
        cam = gp.Camera()
        try:
            if self.port:
                ports = gp.PortInfoList()
                ports.load()
                cam.set_port_info(ports[ports.lookup_path(self.port)])
            cam.init()
        except gp.GPhoto2Error as exc:
            hint = "no camera found: plug it in, switch it on, close other programs using it (gvfs)" \
                if exc.code in (gp.GP_ERROR_MODEL_NOT_FOUND, gp.GP_ERROR_UNKNOWN_PORT) else "check the cable"
            raise HardwareError(f"camera {self.source}: cannot open ({first_line(exc)}); {hint}") from None
        self._handle, self._gp = cam, gp
        self._controls = GPhoto2Controls(cam)

    def _release(self, handle: Any) -> None:
        handle.exit()

    def grab(self) -> Frame:
        """Capture, download and delete one picture; HardwareError (camera closed) when the camera goes away."""
        cam, gp = self._opened(), self._gp
        try:
            path = cam.capture(gp.GP_CAPTURE_IMAGE)
            picture = cam.file_get(path.folder, path.name, gp.GP_FILE_TYPE_NORMAL)
            data = bytes(picture.get_data_and_size())  # copied while the CameraFile lives: the view is its memory
            del picture
            cam.file_delete(path.folder, path.name)
            frame = self._frame(decode(data, f"camera {self.source}: {path.name}"), file=path.name)
        except gp.GPhoto2Error as exc:
            self.close()
            raise HardwareError(f"camera {self.source}: lost during capture ({first_line(exc)}); "
                                "reconnect or switch the camera on, then resume") from None
        return frame


def decode(data: bytes, what: str) -> np.ndarray:
    """8-bit grey from a JPEG / TIFF / PNG file's bytes; HardwareError for raw or broken files.

    The header is checked first: a TIFF-based raw file (NEF, DNG, CR2, ARW) would otherwise be decoded as its
    160x120 preview, and a size over the pixel limit would be decoded before anyone looked.
    """
    try:
        check_image_header(data[:HEADER_BYTES], what, read_at=bytes_reader(data))
        image = imdecode_quiet(data, what, cv2.IMREAD_UNCHANGED)
    except InputError as exc:
        raise HardwareError(f"{exc}, then resume") from None
    if image is None:
        raise HardwareError(f"{what}: not a JPEG or TIFF picture (raw files are not decoded); "
                            "set the camera's image format to JPEG Fine, then resume")
    image = to_8bit(image, 16 if image.dtype == np.uint16 else 8)
    if image.ndim == 3:
        image = colour_to_grey(image, "bgra" if image.shape[2] == 4 else "bgr")
    return image
