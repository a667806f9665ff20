"""Controls of an SDK camera (GenICam node map, pylon, gphoto2 config): read, set, lock for a capture.

A measurement needs exposure, gain, white balance and the trigger fixed: an
automatic mode that changes between frames moves the detected corners. The
names are the same for every SDK: ``exposure`` (us for GenICam; a shutter
speed string for gphoto2), ``gain`` (dB; ISO for gphoto2), ``pixel format``,
``trigger`` and ``white balance`` (its automatic mode). :meth:`lock` switches
every automatic mode off and returns the values a session.json records;
:meth:`apply` puts recorded values back when a capture resumes.

:class:`NodeMapControls` is the GenICam standard feature naming (SFNC) over a
:class:`NodeAccess`, shared by harvesters and pypylon, which differ only in
how a node is read and written.
"""
from __future__ import annotations

import abc
from typing import Protocol

Value = float | str
CHECKED = ("exposure", "gain")  # a frame must report these unchanged (capture/camera_lock.py)


class ControlSurface(abc.ABC):
    """The adjustable controls of one open device."""

    @abc.abstractmethod
    def values(self) -> dict[str, Value]:
        """name -> current value, for the controls the device has."""

    @abc.abstractmethod
    def set(self, name: str, value: Value) -> bool:
        """Switch ``name`` to manual and set it; False when the device refuses or lacks it."""

    def choices(self, name: str) -> tuple[str, ...] | None:
        """The allowed values of an enumerated control (None: numeric or unknown)."""
        return None

    def autos(self) -> dict[str, bool]:
        """name -> automatic mode on, for the controls that have one."""
        return {}

    def set_auto(self, name: str, on: bool) -> bool:
        return False

    def lock(self) -> dict[str, Value]:
        """Automatic modes off, then the values now in force (what session.json records)."""
        for name, on in self.autos().items():
            if on:
                self.set_auto(name, False)
        return self.values()

    def apply(self, recorded: dict[str, Value]) -> list[str]:
        """Set the recorded values (a resumed capture); the names the device would not take back."""
        self.lock()
        now = self.values()
        refused = []
        for name, value in recorded.items():
            if name in now and now[name] != value and not self.set(name, value):
                refused.append(name)
        return refused

    def frame_values(self) -> dict[str, Value]:
        """The checked controls as they were for the frame just grabbed (node values read after the grab)."""
        now = self.values()
        return {k: now[k] for k in CHECKED if k in now}


class NodeAccess(Protocol):
    """Read and write one GenICam feature by name; None / False when the device lacks it or refuses."""

    def read(self, name: str) -> Value | None: ...
    def write(self, name: str, value: Value) -> bool: ...
    def symbolics(self, name: str) -> tuple[str, ...] | None: ...


class GenApiNodes(abc.ABC):
    """:class:`NodeAccess` over a GenApi node map; subclasses name the SDK's own accessors."""

    @abc.abstractmethod
    def _lookup(self, name: str) -> object | None: ...  # the node, None when absent
    @abc.abstractmethod
    def _readable(self, node: object) -> bool: ...
    @abc.abstractmethod
    def _writable(self, node: object) -> bool: ...
    @abc.abstractmethod
    def _get(self, node: object) -> object: ...
    @abc.abstractmethod
    def _put(self, node: object, value: object) -> None: ...
    @abc.abstractmethod
    def _enum(self, node: object) -> tuple[str, ...]: ...

    def _node(self, name: str) -> object | None:
        node = self._lookup(name)
        return node if node is not None and self._readable(node) else None

    def read(self, name: str) -> Value | None:
        node = self._node(name)
        if node is None:
            return None
        try:
            v = self._get(node)
        except Exception:  # a category or command node has no value
            return None
        return v if isinstance(v, str) else float(v) if isinstance(v, (int, float)) else None

    def write(self, name: str, value: Value) -> bool:
        node = self._lookup(name)
        if node is None or not self._writable(node):
            return False
        try:
            self._put(node, value if isinstance(value, str) else type(self._get(node))(value))
        except Exception:  # out of range, wrong type: the device refuses
            return False
        return True

    def symbolics(self, name: str) -> tuple[str, ...] | None:
        node = self._node(name)
        try:
            return tuple(self._enum(node)) if node is not None else None
        except Exception:  # not an enumeration
            return None


# control -> candidate features (the first the device has is used), and the automatic-mode feature
FEATURES: dict[str, tuple[tuple[str, ...], str | None]] = {
    "exposure": (("ExposureTime", "ExposureTimeAbs"), "ExposureAuto"),
    "gain": (("Gain", "GainAbs"), "GainAuto"),
    "pixel format": (("PixelFormat",), None),
    "trigger": (("TriggerMode",), None),
    "white balance": (("BalanceWhiteAuto",), None),
    "frame rate": (("AcquisitionFrameRate", "AcquisitionFrameRateAbs"), None),
}
AUTO_OFF = "Off"


class NodeMapControls(ControlSurface):
    """The SFNC features of a GenICam device (harvesters or pypylon)."""

    def __init__(self, nodes: NodeAccess) -> None:
        self.nodes = nodes
        self._feature: dict[str, str] = {}
        for name, (candidates, _) in FEATURES.items():
            for feature in candidates:
                if nodes.read(feature) is not None:
                    self._feature[name] = feature
                    break

    def values(self) -> dict[str, Value]:
        out: dict[str, Value] = {}
        for name, feature in self._feature.items():
            v = self.nodes.read(feature)
            if v is not None:
                out[name] = v if isinstance(v, str) else float(v)
        return out

    def set(self, name: str, value: Value) -> bool:
        feature = self._feature.get(name)
        if feature is None:
            return False
        self.set_auto(name, False)
        return self.nodes.write(feature, value)

    def choices(self, name: str) -> tuple[str, ...] | None:
        feature = self._feature.get(name)
        return None if feature is None else self.nodes.symbolics(feature)

    def autos(self) -> dict[str, bool]:
        out = {}
        for name in self._feature:
            auto = FEATURES[name][1]
            if auto is not None:
                v = self.nodes.read(auto)
                if isinstance(v, str):
                    out[name] = v != AUTO_OFF
        if isinstance(self.values().get("white balance"), str):
            out["white balance"] = self.values()["white balance"] != AUTO_OFF
        return out

    def set_auto(self, name: str, on: bool) -> bool:
        if name == "white balance":
            feature = self._feature.get(name)
        else:
            feature = FEATURES[name][1] if name in FEATURES else None
        if feature is None or self.nodes.read(feature) is None:
            return False
        want = "Continuous" if on else AUTO_OFF
        return self.nodes.read(feature) == want or self.nodes.write(feature, want)
