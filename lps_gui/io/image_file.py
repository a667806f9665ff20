"""Reading an image file with its limits checked first: file size, then pixel count, then decode.

Every reader of user or session images goes through :func:`read_image`, so
a tiny file that decodes to gigabytes, a device file or a huge file is
refused with one line instead of exhausting memory.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

from lps_gui.core.image_header import HEADER_BYTES, check_image_header
from lps_gui.errors import InputError

MAX_IMAGE_BYTES = 1 << 30  # 1 GB on disk


def read_file_limited(path: Path | str, max_bytes: int = MAX_IMAGE_BYTES, what: str = "image",
                      follow_symlinks: bool = True) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (not a device, FIFO or folder)."""
    path = Path(path)
    flags = os.O_RDONLY | (0 if follow_symlinks else getattr(os, "O_NOFOLLOW", 0)) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise InputError(f"{path}: {what} not found; check the path") from None
    except OSError as exc:
        if not follow_symlinks and path.is_symlink():
            raise InputError(f"{path}: is a symbolic link; session files must be regular files inside the session folder") from None
        raise InputError(f"{path}: cannot read the {what} ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"{path}: not a regular file; give an {what} file")
        if st.st_size > max_bytes:
            raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB, over the {max_bytes / 1e6:.0f} MB limit for an {what}")
        return f.read(max_bytes + 1)


def decode_image(data: bytes, name: str, flags: int | None = None) -> np.ndarray | None:
    """Decode bytes after the header check; None when OpenCV cannot decode them."""
    import cv2

    check_image_header(data[:HEADER_BYTES], name)
    if not data:
        return None
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE if flags is None else flags)


def read_image(path: Path | str, flags: int | None = None) -> np.ndarray:
    """An image file decoded (grey by default), or InputError naming the file."""
    image = decode_image(read_file_limited(path), str(path), flags)
    if image is None:
        raise InputError(f"{path}: not an image OpenCV can read (or truncated); check the file")
    return image
