"""A GigE Vision / USB3 Vision camera through harvesters and a GenTL producer (``genicam:SERIAL``).

Any vendor's GenTL producer (a ``.cti`` file: Basler, FLIR Spinnaker, Allied
Vision Vimba, MATRIX VISION mvGenTL...) opens the device; it comes from
``--cti PATH`` or the standard ``GENICAM_GENTL64_PATH`` (folders holding .cti
files, ``os.pathsep`` separated). The genicam wheel bundles a demo producer,
``viky.cti`` (three virtual devices, serials 0..2, 400x400), used by the tests.
Each grab starts the acquisition if needed and fetches the next buffer;
controls are the SFNC features of the remote device's node map.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.control_surface import ControlSurface, NodeMapControls, Value
from lps_gui.camera.extras import first_line, import_sdk
from lps_gui.camera.pixels import BayerGrey, is_supported, to_grey8
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import HardwareError, InputError

FETCH_TIMEOUT_S = 5.0
GENTL_ENV = "GENICAM_GENTL64_PATH"


def producer_files(cti: str | None, source: str) -> list[str]:
    """The .cti files to load: ``cti`` (a file) or every .cti in the folders of GENICAM_GENTL64_PATH."""
    if cti:
        if not Path(cti).is_file():
            raise InputError(f"camera {source}: GenTL producer {cti} not found; give the .cti file of the camera vendor's SDK")
        return [str(cti)]
    files = [str(p) for d in os.environ.get(GENTL_ENV, "").split(os.pathsep) if d and Path(d).is_dir()
             for p in sorted(Path(d).glob("*.cti"))]
    if not files:
        raise InputError(
            f"camera {source}: no GenTL producer; give --cti PATH (the vendor's .cti file) or set {GENTL_ENV}"
        )
    return files


def demo_producer() -> str | None:
    """The viky.cti demo producer bundled with the genicam wheel, if installed."""
    try:
        genicam = import_sdk("genicam", "genicam:")
    except InputError:
        return None
    path = Path(genicam.__file__).with_name("viky.cti")
    return str(path) if path.is_file() else None


class HarvesterNodes:
    """:class:`NodeAccess` over a harvesters (genicam.genapi) node map."""

    def __init__(self, node_map: Any, genapi: Any) -> None:
        self.node_map, self.genapi = node_map, genapi

    def _node(self, name: str) -> Any:
        if not self.node_map.has_node(name):
            return None
        node = getattr(self.node_map, name)
        return node if self.genapi.is_readable(node) else None

    def read(self, name: str) -> Value | None:
        node = self._node(name)
        if node is None:
            return None
        try:
            v = node.value
        except Exception:  # a category or command node has no value
            return None
        return v if isinstance(v, str) else float(v) if isinstance(v, (int, float)) else None

    def write(self, name: str, value: Value) -> bool:
        node = getattr(self.node_map, name) if self.node_map.has_node(name) else None
        if node is None or not self.genapi.is_writable(node):
            return False
        try:
            node.value = value if isinstance(value, str) else type(node.value)(value)
        except Exception:  # out of range, wrong type: the device refuses
            return False
        return True

    def symbolics(self, name: str) -> tuple[str, ...] | None:
        node = self._node(name)
        try:
            return tuple(node.symbolics) if node is not None else None
        except Exception:  # not an enumeration
            return None


def list_genicam_devices(cti: str | None = None) -> list[tuple[str, str]]:
    """(label, source) of the devices the producers find; empty without a producer."""
    try:
        files = producer_files(cti, "genicam:")
    except InputError:
        return []
    h = _harvester(files, "genicam:")
    try:
        return [(f"{d.vendor} {d.model} ({d.serial_number})", f"genicam:{d.serial_number}") for d in h.device_info_list]
    finally:
        h.reset()


def _harvester(files: list[str], source: str) -> Any:
    core = import_sdk("harvesters.core", source)
    h = core.Harvester()
    for f in files:
        h.add_file(f, check_existence=True, check_validity=True)
    h.update()
    return h


class GenICamCamera(Camera):
    """:class:`Camera` over a harvesters ``ImageAcquirer``; frames 8-bit grey (mono and Bayer without demosaic)."""

    def __init__(self, serial: str = "", cti: str | None = None, clock: Clock | None = None) -> None:
        self.serial = serial
        self.cti = cti
        self.source = f"genicam:{serial}"
        self.clock = clock or RealClock()
        self._h: Any = None
        self._ia: Any = None
        self._controls: NodeMapControls | None = None
        self._bayer = BayerGrey()
        self._frame_no = 0

    def open(self) -> None:
        if self._ia is not None:
            return
        files = producer_files(self.cti, self.source)
        genapi = import_sdk("genicam.genapi", self.source)
        h = _harvester(files, self.source)
        try:
            ia = h.create({"serial_number": self.serial} if self.serial else 0)
        except Exception as exc:  # ValueError: no such serial; a GenTL error: in use
            found = ", ".join(d.serial_number for d in h.device_info_list) or "none"
            h.reset()
            raise HardwareError(f"camera {self.source}: cannot open ({first_line(exc)}); serials found: {found}") from None
        self._h, self._ia = h, ia
        self._controls = NodeMapControls(HarvesterNodes(ia.remote_device.node_map, genapi))
        self._frame_no = 0

    @property
    def is_open(self) -> bool:
        return self._ia is not None

    def close(self) -> None:
        ia, h, self._ia, self._h, self._controls = self._ia, self._h, None, None, None
        for fn in ((ia.stop, ia.destroy) if ia is not None else ()) + ((h.reset,) if h is not None else ()):
            try:
                fn()
            except Exception:  # a vanished device cannot be released: it is gone either way
                pass

    def control_surface(self) -> ControlSurface | None:
        return self._controls

    @property
    def node_map(self) -> Any:
        """The remote device's node map (for features outside the common controls)."""
        if self._ia is None:
            raise HardwareError(f"camera {self.source}: not open; open the camera first")
        return self._ia.remote_device.node_map

    def grab(self) -> Frame:
        if self._ia is None:
            raise HardwareError(f"camera {self.source}: grab before open(); open the camera first")
        try:
            if not self._ia.is_acquiring():
                self._ia.start()
            with self._ia.fetch(timeout=FETCH_TIMEOUT_S) as buf:
                c = buf.payload.components[0]
                fmt = str(c.data_format)
                if not is_supported(fmt):
                    raise HardwareError(f"camera {self.source}: pixel format {fmt} is not handled; set PixelFormat to Mono8")
                channels = int(round(c.num_components_per_pixel)) or 1
                shape = (c.height, c.width) if channels == 1 else (c.height, c.width, channels)
                data = np.array(c.data, copy=True).reshape(shape)
        except HardwareError:
            raise
        except Exception as exc:  # fetch timeout, a removed device
            self.close()
            raise HardwareError(f"camera {self.source}: no frame ({first_line(exc)}); check the cable, then resume") from None
        image = to_grey8(data, fmt, self._bayer)
        self._frame_no += 1
        meta: dict[str, Any] = {"frame": self._frame_no, "pixel_format": fmt}
        if self._controls is not None:
            meta["controls"] = self._controls.frame_values()
        return Frame(image=image, time=self.clock.now(), meta=meta)

    def properties(self) -> dict[str, Any]:
        out: dict[str, Any] = {"driver": "GenICamCamera", "source": self.source, "channels": 1, "cti": self.cti}
        if self._ia is not None:
            info = self._ia.device.module  # the GenTL device: vendor and model as the producer reports them
            nm = self._ia.remote_device.node_map
            out.update(model=str(getattr(info, "model", "")), serial=self.serial,
                       width=int(nm.Width.value), height=int(nm.Height.value))
            if self._controls is not None:
                out["controls"] = self._controls.values()
        return out
