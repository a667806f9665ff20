"""A Linux V4L2 device by its node (``v4l2:/dev/videoN``), through OpenCV's V4L2 back end.

Unlike a bare device index, the node name is stable for a given port when a
udev rule or /dev/v4l/by-id gives it; the controls (exposure, gain, focus,
white balance) are the device's V4L2 controls as OpenCV exposes them
(``camera/controls.py``).
"""
from __future__ import annotations

import glob
import os
import re
from pathlib import Path
from typing import Any

import cv2

from lps_gui.camera.opencv_camera import OpenCVCamera
from lps_gui.errors import InputError


def list_v4l2_devices() -> list[tuple[str, str]]:
    """(label, source) of every /dev/video* node (a device may show several: capture and metadata nodes)."""
    out = []
    for node in sorted(glob.glob("/dev/video*")):
        name = Path(f"/sys/class/video4linux/{Path(node).name}/name")
        label = name.read_text().strip() if name.is_file() else node
        out.append((f"{label} ({node})", f"v4l2:{node}"))
    return out


def node_index(node: str) -> int:
    """N of /dev/videoN, following a /dev/v4l/by-id or udev symlink (OpenCV's V4L2 back end opens by index)."""
    m = re.fullmatch(r"/dev/video(\d+)", os.path.realpath(node))
    if m is None:
        raise InputError(f"camera v4l2:{node}: not a /dev/videoN node (or a link to one); see `ls /dev/video*`")
    return int(m.group(1))


class V4L2Camera(OpenCVCamera):
    """:class:`OpenCVCamera` on a V4L2 node, with the device's controls."""

    backend = cv2.CAP_V4L2
    device_controls = True

    def __init__(self, node: str, **options: Any) -> None:
        self.node = node
        super().__init__(node_index(node), **options)

    @property
    def _name(self) -> str:
        return f"camera v4l2:{self.node}"

    def properties(self) -> dict[str, Any]:
        return {**super().properties(), "driver": "V4L2Camera", "source": f"v4l2:{self.node}"}
