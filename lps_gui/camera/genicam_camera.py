"""A GigE Vision / USB3 Vision camera through harvesters and a GenTL producer (``genicam:SERIAL``).

Any vendor's GenTL producer (a ``.cti`` file: Basler, FLIR Spinnaker, Allied
Vision Vimba, MATRIX VISION mvGenTL...) opens the device; it comes from
``--cti PATH`` or the standard ``GENICAM_GENTL64_PATH`` (folders holding .cti
files, ``os.pathsep`` separated). The genicam wheel bundles a demo producer,
``viky.cti`` (three virtual devices, serials 0..2, 400x400), used by the tests.
Each grab is a fresh acquisition (start, fetch, stop: no buffer queued
during a move is ever taken); streaming (the preview) keeps the acquisition
running and fetches the next buffer. Controls are the SFNC features of the
remote device's node map.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.camera.base import Frame
from lps_gui.camera.control_surface import GenApiNodes, NodeMapControls
from lps_gui.camera.extras import first_line, genicam_package, harvesters_sdk
from lps_gui.camera.pixels import is_supported
from lps_gui.camera.sdk_device import SdkCamera
from lps_gui.core.clock import Clock
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
        genicam = genicam_package("genicam:")
    except InputError:
        return None
    path = Path(genicam.__file__).with_name("viky.cti")
    return str(path) if path.is_file() else None


class HarvesterNodes(GenApiNodes):
    """:class:`NodeAccess` over a harvesters (genicam.genapi) node map."""

    def __init__(self, node_map: Any, genapi: Any) -> None:
        self.node_map, self.genapi = node_map, genapi

    def _lookup(self, name: str) -> Any:
        return getattr(self.node_map, name) if self.node_map.has_node(name) else None

    def _readable(self, node: Any) -> bool:
        return bool(self.genapi.is_readable(node))

    def _writable(self, node: Any) -> bool:
        return bool(self.genapi.is_writable(node))

    def _get(self, node: Any) -> Any:
        return node.value

    def _put(self, node: Any, value: Any) -> None:
        node.value = value

    def _enum(self, node: Any) -> tuple[str, ...]:
        return tuple(node.symbolics)


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
    core, _ = harvesters_sdk(source)
    h = core.Harvester()
    for f in files:
        h.add_file(f, check_existence=True, check_validity=True)
    h.update()
    return h


class GenICamCamera(SdkCamera):
    """:class:`Camera` over a harvesters ``ImageAcquirer``; frames 8-bit grey (mono and Bayer without demosaic)."""

    driver = "GenICamCamera"

    def __init__(self, serial: str = "", cti: str | None = None, clock: Clock | None = None) -> None:
        super().__init__(f"genicam:{serial}", clock)
        self.serial, self.cti = serial, cti
        self._h: Any = None

    def open(self) -> None:
        if self._handle is not None:
            return
        files = producer_files(self.cti, self.source)
        _, genapi = harvesters_sdk(self.source)
        h = _harvester(files, self.source)
        try:
            ia = h.create({"serial_number": self.serial} if self.serial else 0)
        except Exception as exc:  # ValueError: no such serial; a GenTL error: in use
            found = ", ".join(d.serial_number for d in h.device_info_list) or "none"
            h.reset()
            raise HardwareError(f"camera {self.source}: cannot open ({first_line(exc)}); serials found: {found}") from None
        self._h, self._handle = h, ia
        self._controls = NodeMapControls(HarvesterNodes(ia.remote_device.node_map, genapi))

    def _release(self, handle: Any) -> None:
        h, self._h = self._h, None
        try:
            handle.stop()
            handle.destroy()
        finally:
            if h is not None:
                h.reset()

    def _stop_stream(self, handle: Any) -> None:
        handle.stop()

    @property
    def node_map(self) -> Any:
        """The remote device's node map (for features outside the common controls)."""
        return self._opened().remote_device.node_map

    def grab(self) -> Frame:
        with self._grab_lock:
            return self._grab()

    def _grab(self) -> Frame:
        ia = self._opened()
        try:
            if not ia.is_acquiring():
                ia.start()
            with ia.fetch(timeout=FETCH_TIMEOUT_S) as buf:
                c = buf.payload.components[0]
                fmt = str(c.data_format)
                if not is_supported(fmt):
                    raise HardwareError(f"camera {self.source}: pixel format {fmt} is not handled; set PixelFormat to Mono8")
                channels = int(round(c.num_components_per_pixel)) or 1
                shape = (c.height, c.width) if channels == 1 else (c.height, c.width, channels)
                data = np.array(c.data, copy=True).reshape(shape)
            if not self.streaming:
                ia.stop()
        except HardwareError:  # a format not handled: no acquisition left running to buffer frames during a move
            if not self.streaming:
                try:
                    ia.stop()
                except Exception:  # a device gone as well: the next grab reopens it
                    self.close()
            raise
        except Exception as exc:  # fetch timeout, a removed device
            self.close()
            raise HardwareError(f"camera {self.source}: no frame ({first_line(exc)}); check the cable, then resume") from None
        return self._frame(data, fmt)

    def properties(self) -> dict[str, Any]:
        out = {**super().properties(), "cti": self.cti}
        if self._handle is not None:
            nm = self._handle.remote_device.node_map
            out.update(model=str(getattr(self._handle.device.module, "model", "")), serial=self.serial,
                       width=int(nm.Width.value), height=int(nm.Height.value))
        return out
