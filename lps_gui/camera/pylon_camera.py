"""A Basler camera through pypylon (``pylon:SERIAL``; ``pylon:`` takes the first device found).

Each :meth:`PylonCamera.grab` is one ``GrabOne``: acquisition starts after
the call, so the frame is exposed after the stage settled, never a buffered
one from before the move; streaming (the preview) grabs continuously with
``GrabStrategy_LatestImageOnly``. Controls are the GenICam features of the node map
(:class:`~lps_gui.camera.control_surface.NodeMapControls`). Without a camera,
``PYLON_CAMEMU=N`` makes pylon offer N emulated cameras (serials 0815-0000...)
whose ``ImageFilename`` feature returns a given image byte for byte.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.camera.base import Frame
from lps_gui.camera.control_surface import GenApiNodes, NodeMapControls
from lps_gui.camera.extras import first_line, pylon_sdk
from lps_gui.camera.sdk_device import SdkCamera
from lps_gui.core.clock import Clock
from lps_gui.errors import HardwareError

GRAB_TIMEOUT_MS = 5000


class PylonNodes(GenApiNodes):
    """:class:`NodeAccess` over a pypylon node map."""

    def __init__(self, node_map: Any, genicam: Any) -> None:
        self.node_map, self.genicam = node_map, genicam

    def _lookup(self, name: str) -> Any:
        return self.node_map.GetNode(name)

    def _readable(self, node: Any) -> bool:
        return bool(self.genicam.IsReadable(node))

    def _writable(self, node: Any) -> bool:
        return bool(self.genicam.IsWritable(node))

    def _get(self, node: Any) -> Any:
        return node.GetValue()

    def _put(self, node: Any, value: Any) -> None:
        node.SetValue(value)

    def _enum(self, node: Any) -> tuple[str, ...]:
        return tuple(node.GetSymbolics())


BUFFER_LAYOUTS = {"BGRA8Packed": (4, np.uint8), "RGB16Packed": (3, np.uint16)}  # GetArray refuses these


def grab_array(result: Any, pixel_format: str) -> np.ndarray:
    """The grab result's pixels as an array; the formats ``GetArray`` does not support are read from the raw buffer."""
    if pixel_format not in BUFFER_LAYOUTS:
        return result.GetArray()
    channels, dtype = BUFFER_LAYOUTS[pixel_format]
    h, w = int(result.Height), int(result.Width)
    rows = np.frombuffer(result.GetBuffer(), dtype=dtype)
    if rows.size < h * w * channels:
        raise HardwareError(f"camera: a {pixel_format} buffer of {rows.nbytes} bytes is short for {w}x{h}; resume to retry")
    return rows[: h * (rows.size // h)].reshape(h, -1)[:, : w * channels].reshape(h, w, channels)


def list_pylon_devices() -> list[tuple[str, str]]:
    """(label, source) of every device pylon finds (emulated ones under PYLON_CAMEMU)."""
    pylon, _ = pylon_sdk("pylon:")
    return [(f"{d.GetFriendlyName()}", f"pylon:{d.GetSerialNumber()}") for d in pylon.TlFactory.GetInstance().EnumerateDevices()]


class PylonCamera(SdkCamera):
    """:class:`Camera` over a pypylon ``InstantCamera``; frames 8-bit grey (mono and Bayer without demosaic)."""

    driver = "PylonCamera"

    def __init__(self, serial: str = "", clock: Clock | None = None) -> None:
        super().__init__(f"pylon:{serial}", clock)
        self.serial = serial

    def open(self) -> None:
        if self._handle is not None:
            return
        pylon, genicam = pylon_sdk(self.source)
        factory = pylon.TlFactory.GetInstance()
        try:
            if self.serial:
                info = pylon.DeviceInfo()
                info.SetSerialNumber(self.serial)
                device = factory.CreateDevice(info)
            else:
                device = factory.CreateFirstDevice()
            cam = pylon.InstantCamera(device)
            cam.Open()
        except Exception as exc:  # genicam.RuntimeException: no such device, in use, no permission
            raise HardwareError(
                f"camera {self.source}: cannot open ({first_line(exc)}); check the serial, the cable and pylon Viewer"
            ) from None
        self._handle, self._pylon = cam, pylon
        self._controls = NodeMapControls(PylonNodes(cam.GetNodeMap(), genicam))

    def _release(self, handle: Any) -> None:
        handle.Close()

    def _stop_stream(self, handle: Any) -> None:
        handle.StopGrabbing()

    @property
    def device(self) -> Any:
        """The open ``InstantCamera`` (for features outside the common controls)."""
        return self._opened()

    def grab(self) -> Frame:
        with self._grab_lock:
            return self._grab()

    def _grab(self) -> Frame:
        cam = self.device
        try:
            if not self.streaming:
                result = cam.GrabOne(GRAB_TIMEOUT_MS)
            else:
                if not cam.IsGrabbing():
                    cam.StartGrabbing(self._pylon.GrabStrategy_LatestImageOnly)
                result = cam.RetrieveResult(GRAB_TIMEOUT_MS, self._pylon.TimeoutHandling_ThrowException)
        except Exception as exc:  # timeout or a removed device
            self.close()
            raise HardwareError(f"camera {self.source}: no frame ({first_line(exc)}); check the cable, then resume") from None
        try:  # the camera can vanish between GrabOne and these node reads: same one line as a lost grab
            try:
                if not result.GrabSucceeded():
                    raise HardwareError(f"camera {self.source}: grab failed ({result.GetErrorDescription()}); resume to retry")
                fmt = str(cam.PixelFormat.GetValue())
                data = grab_array(result, fmt)
            finally:
                result.Release()
            return self._frame(data, fmt)
        except HardwareError:
            raise
        except Exception as exc:  # genicam.LogicalErrorException, RuntimeException: the device is gone
            self.close()
            raise HardwareError(f"camera {self.source}: lost after the grab ({first_line(exc)}); "
                                "check the cable, then resume") from None

    def properties(self) -> dict[str, Any]:
        out = super().properties()
        if self._handle is not None:
            info = self._handle.GetDeviceInfo()
            out.update(model=info.GetModelName(), serial=info.GetSerialNumber(),
                       width=int(self._handle.Width.GetValue()), height=int(self._handle.Height.GetValue()))
        return out
