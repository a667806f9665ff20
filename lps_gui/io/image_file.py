"""Reading an image file with its limits checked first: file size, then pixel count, then decode.

Every reader of user or session images goes through :func:`read_image`, so
a tiny file that decodes to gigabytes, a device file or a huge file is
refused with one line instead of exhausting memory.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from lps_gui.core.image_header import HEADER_BYTES, bytes_reader, check_image_header
from lps_gui.errors import InputError
from lps_gui.file_limits import (  # re-exported: every reader's way in
    MAX_FILE_BYTES,
    check_regular_file,
    read_file_limited,
)

MAX_IMAGE_BYTES = MAX_FILE_BYTES  # 1 GB on disk
__all__ = ["MAX_IMAGE_BYTES", "check_regular_file", "decode_image", "read_file_limited", "read_image"]


def decode_image(data: bytes, name: str, flags: int | None = None) -> np.ndarray | None:
    """Decode bytes after the header check; None when OpenCV cannot decode them (its own lines kept off stderr)."""
    import cv2

    from lps_gui.quiet_decode import imdecode_quiet  # cv2 only where an image is decoded (lps estimate never does)

    check_image_header(data[:HEADER_BYTES], name, read_at=bytes_reader(data))
    if not data:
        return None
    return imdecode_quiet(data, name, cv2.IMREAD_GRAYSCALE if flags is None else flags)


def image_size(path: Path | str) -> tuple[int, int]:
    """(width, height) of an image file from its header (checked like every read), decoding only formats without one."""
    path = Path(path)
    st = check_regular_file(path, "image")
    if st.st_size > MAX_IMAGE_BYTES:
        raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB, over the {MAX_IMAGE_BYTES / 1e6:.0f} MB limit for an image")
    with open(path, "rb") as f:
        size = check_image_header(f.read(HEADER_BYTES), str(path), read_at=lambda offset, n: os.pread(f.fileno(), n, offset))
    if size is None:
        image = read_image(path)
        size = (image.shape[1], image.shape[0])
    return size


def read_image(path: Path | str, flags: int | None = None) -> np.ndarray:
    """An image file decoded (grey by default), or InputError naming the file."""
    image = decode_image(read_file_limited(path), str(path), flags)
    if image is None:
        raise InputError(f"{path}: not an image OpenCV can read (or truncated); check the file")
    return image
