"""A Basler camera through pypylon (``pylon:SERIAL``; ``pylon:`` takes the first device found).

Each :meth:`PylonCamera.grab` is one ``GrabOne``: acquisition starts after
the call, so the frame is exposed after the stage settled, never a buffered
one from before the move. Controls are the GenICam features of the node map
(:class:`~lps_gui.camera.control_surface.NodeMapControls`). Without a camera,
``PYLON_CAMEMU=N`` makes pylon offer N emulated cameras (serials 0815-0000...)
whose ``ImageFilename`` feature returns a given image byte for byte.
"""
from __future__ import annotations

from typing import Any

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.control_surface import ControlSurface, NodeMapControls, Value
from lps_gui.camera.extras import first_line, import_sdk
from lps_gui.camera.pixels import BayerGrey, to_grey8
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import HardwareError

GRAB_TIMEOUT_MS = 5000


class PylonNodes:
    """:class:`NodeAccess` over a pypylon node map."""

    def __init__(self, node_map: Any, genicam: Any) -> None:
        self.node_map, self.genicam = node_map, genicam

    def _node(self, name: str) -> Any:
        node = self.node_map.GetNode(name)
        return node if node is not None and self.genicam.IsReadable(node) else None

    def read(self, name: str) -> Value | None:
        node = self._node(name)
        if node is None:
            return None
        try:
            v = node.GetValue()
        except Exception:  # a category or command node has no value
            return None
        return v if isinstance(v, str) else float(v) if isinstance(v, (int, float)) else None

    def write(self, name: str, value: Value) -> bool:
        node = self.node_map.GetNode(name)
        if node is None or not self.genicam.IsWritable(node):
            return False
        try:
            node.SetValue(value if isinstance(value, str) else type(node.GetValue())(value))
        except Exception:  # out of range, wrong type: the device refuses
            return False
        return True

    def symbolics(self, name: str) -> tuple[str, ...] | None:
        node = self._node(name)
        try:
            return tuple(node.GetSymbolics()) if node is not None else None
        except Exception:  # not an enumeration
            return None


def list_pylon_devices() -> list[tuple[str, str]]:
    """(label, source) of every device pylon finds (emulated ones under PYLON_CAMEMU)."""
    pylon = import_sdk("pypylon.pylon", "pylon:")
    return [(f"{d.GetFriendlyName()}", f"pylon:{d.GetSerialNumber()}") for d in pylon.TlFactory.GetInstance().EnumerateDevices()]


class PylonCamera(Camera):
    """:class:`Camera` over a pypylon ``InstantCamera``; frames 8-bit grey (mono and Bayer without demosaic)."""

    def __init__(self, serial: str = "", clock: Clock | None = None) -> None:
        self.serial = serial
        self.source = f"pylon:{serial}"
        self.clock = clock or RealClock()
        self._cam: Any = None
        self._controls: NodeMapControls | None = None
        self._bayer = BayerGrey()
        self._frame_no = 0

    def open(self) -> None:
        if self._cam is not None:
            return
        pylon = import_sdk("pypylon.pylon", self.source)
        genicam = import_sdk("pypylon.genicam", self.source)
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
        self._cam, self._pylon = cam, pylon
        self._controls = NodeMapControls(PylonNodes(cam.GetNodeMap(), genicam))
        self._frame_no = 0

    @property
    def is_open(self) -> bool:
        return self._cam is not None

    def close(self) -> None:
        cam, self._cam, self._controls = self._cam, None, None
        if cam is not None:
            try:
                cam.Close()
            except Exception:  # a vanished device cannot be closed: it is gone either way
                pass

    @property
    def device(self) -> Any:
        """The open ``InstantCamera`` (for features outside the common controls)."""
        if self._cam is None:
            raise HardwareError(f"camera {self.source}: not open; open the camera first")
        return self._cam

    def control_surface(self) -> ControlSurface | None:
        return self._controls

    def grab(self) -> Frame:
        cam = self.device
        try:
            result = cam.GrabOne(GRAB_TIMEOUT_MS)
        except Exception as exc:  # timeout or a removed device
            self.close()
            raise HardwareError(f"camera {self.source}: no frame ({first_line(exc)}); check the cable, then resume") from None
        try:
            if not result.GrabSucceeded():
                raise HardwareError(f"camera {self.source}: grab failed ({result.GetErrorDescription()}); resume to retry")
            data = result.GetArray()
        finally:
            result.Release()
        fmt = str(self._controls.values().get("pixel format", "Mono8")) if self._controls else "Mono8"
        image = to_grey8(data, fmt, self._bayer)
        self._frame_no += 1
        meta: dict[str, Any] = {"frame": self._frame_no, "pixel_format": fmt}
        if self._controls is not None:
            meta["controls"] = self._controls.frame_values()
        return Frame(image=image, time=self.clock.now(), meta=meta)

    def properties(self) -> dict[str, Any]:
        out: dict[str, Any] = {"driver": "PylonCamera", "source": self.source, "channels": 1}
        if self._cam is not None:
            info = self._cam.GetDeviceInfo()
            out.update(model=info.GetModelName(), serial=info.GetSerialNumber(),
                       width=int(self._cam.Width.GetValue()), height=int(self._cam.Height.GetValue()))
            if self._controls is not None:
                out["controls"] = self._controls.values()
        return out
