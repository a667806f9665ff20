"""Replay a folder of images as a camera, in order: re-run a capture or test without hardware.

A capture session folder (with captures.jsonl) replays its listed frames in
capture-index order; any other folder replays its image files in natural
name order (``img2`` before ``img10``).
"""
from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.opencv_camera import _to_8bit
from lps_gui.core.clock import Clock, RealClock
from lps_gui.errors import HardwareError, InputError
from lps_gui.file_limits import read_file_limited, resolve_in_session

IMAGE_EXTENSIONS = (".png", ".tif", ".tiff", ".bmp", ".jpg", ".jpeg", ".pgm", ".ppm", ".webp")


def natural_key(name: str) -> list[Any]:
    """Sort key that orders the digit runs of a name by value."""
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name)]


def list_images(folder: Path) -> list[Path]:
    """The images of ``folder`` in replay order (see module docstring)."""
    captures = folder / "captures.jsonl"
    if captures.is_file():
        rows = {}
        try:
            text = read_file_limited(captures, 1 << 30, "captures file", follow_symlinks=False).decode("utf-8")
        except UnicodeDecodeError:
            raise InputError(f"{captures}: not a text file (binary content); fix or restore it") from None
        for n, line in enumerate(text.splitlines(), 1):
            try:
                d = json.loads(line)
                index, file = int(d["index"]), str(d["file"])
            except (json.JSONDecodeError, KeyError, TypeError, ValueError):
                continue  # a torn last line: not listed
            # a replayed session is confined like any other: no ../../outside/secret.png, no /dev/zero
            rows[index] = resolve_in_session(folder, file, f"{captures}: line {n}")
        return [rows[i] for i in sorted(rows)]
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS]
    return sorted(files, key=lambda p: natural_key(p.name))


class FolderReplayCamera(Camera):
    """:class:`Camera` that returns the images of a folder one per grab.

    Parameters
    ----------
    folder : a folder of images, or a capture session folder.
    loop : start again after the last image instead of failing.
    grey : return 8-bit grey frames (H, W).
    clock : timestamps frames.
    """

    def __init__(self, folder: Path | str, loop: bool = False, grey: bool = True, clock: Clock | None = None) -> None:
        self.folder = Path(folder)
        self.loop = loop
        self.grey = grey
        self.clock = clock or RealClock()
        self.files: list[Path] = []
        self._next = 0
        self._open = False
        self._size: tuple[int, int] | None = None

    def open(self) -> None:
        if not self.folder.is_dir():
            raise InputError(f"{self.folder}: image folder not found; check the path")
        self.files = list_images(self.folder)
        if not self.files:
            raise InputError(f"{self.folder}: no images ({', '.join(IMAGE_EXTENSIONS)}) to replay")
        self._next = 0
        self._open = True

    def __len__(self) -> int:
        return len(self.files)

    def grab(self) -> Frame:
        """The next image; HardwareError after the last one (unless ``loop``) or if it cannot be read."""
        if not self._open:
            raise HardwareError(f"folder replay {self.folder}: grab before open(); open the camera first")
        if self._next >= len(self.files):
            if not self.loop:
                raise HardwareError(f"folder replay {self.folder}: all {len(self.files)} images replayed; add images or use loop")
            self._next = 0
        path = self.files[self._next]
        image = _read_checked(path)
        if image is None:
            raise HardwareError(f"{path}: cannot read this image; replace or remove it")
        image = _to_8bit(image, self.grey)
        self._next += 1
        self._size = (image.shape[1], image.shape[0])
        return Frame(image=image, time=self.clock.now(), meta={"frame": self._next, "file": path.name})

    def properties(self) -> dict[str, Any]:
        out: dict[str, Any] = {"driver": "FolderReplayCamera", "folder": str(self.folder), "n_images": len(self.files)}
        out["channels"] = 1 if self.grey else 3
        if self._size is None and self.files:
            first = _read_checked(self.files[0])
            if first is not None:
                self._size = (first.shape[1], first.shape[0])
        if self._size is not None:
            out["width"], out["height"] = self._size
        return out


def _read_checked(path: Path) -> np.ndarray | None:
    """Decode ``path`` after checking its header's pixel count (a tiny file can decode to gigabytes)."""
    from lps_gui.core.image_header import bytes_reader, check_image_header
    from lps_gui.quiet_decode import imdecode_quiet

    try:
        data = read_file_limited(path, what="image", follow_symlinks=False)
    except InputError as exc:
        raise HardwareError(str(exc)) from None
    check_image_header(data[:1 << 16], str(path), read_at=bytes_reader(data))
    return imdecode_quiet(data, str(path), cv2.IMREAD_UNCHANGED) if data else None
