"""Image size from a file's first bytes, before anything is decoded.

A 30000x30000 PNG is under a megabyte on disk and 900 MB (grey) to 2.7 GB
(colour) once decoded, plus the decoder's working copies: every reader
checks the pixel count from the header first and refuses an image over
:data:`MAX_IMAGE_PIXELS` with a one-line error. Pure bytes in, numbers out
(no I/O), so every layer may use it.
"""
from __future__ import annotations

import struct
from typing import Callable

from lps_gui.errors import InputError

MAX_IMAGE_PIXELS = 100_000_000  # 100 Mpx: above any machine-vision camera, far below an out-of-memory
HEADER_BYTES = 1 << 16  # enough for the headers below (JPEG SOF after large EXIF blocks may need more)


def _png(head: bytes) -> tuple[int, int] | None:
    if head[:8] == b"\x89PNG\r\n\x1a\n" and len(head) >= 24 and head[12:16] == b"IHDR":
        return struct.unpack(">II", head[16:24])
    return None


def _bmp(head: bytes) -> tuple[int, int] | None:
    if head[:2] == b"BM" and len(head) >= 26:
        w, h = struct.unpack("<ii", head[18:26])
        return abs(w), abs(h)
    return None


def _jpeg(head: bytes) -> tuple[int, int] | None:
    if head[:2] != b"\xff\xd8":
        return None
    i = 2
    while i + 9 < len(head):
        if head[i] != 0xFF:
            i += 1
            continue
        marker = head[i + 1]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7 or marker == 0xFF:
            i += 1 if marker == 0xFF else 2
            continue
        length = struct.unpack(">H", head[i + 2 : i + 4])[0]
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            h, w = struct.unpack(">HH", head[i + 5 : i + 9])
            return w, h
        i += 2 + length
    return None


ReadAt = Callable[[int, int], bytes]  # (offset, size) -> the bytes of the file there (fewer at its end)


class _Unreachable(Exception):
    """The TIFF's image directory lies beyond the bytes given and no ``read_at`` can fetch it."""


def _tiff(head: bytes, read_at: ReadAt | None = None) -> tuple[int, int] | None:
    """Width and height from the first image directory (IFD), wherever in the file it is.

    OpenCV writes the IFD after the image data, so for anything but a tiny image it is not in the first
    64 KB: ``read_at`` fetches it (the caller has the file or its bytes); without one the TIFF is unreachable.
    """
    if head[:4] not in (b"II*\x00", b"MM\x00*"):
        return None
    e = "<" if head[:2] == b"II" else ">"

    def get(offset: int, size: int) -> bytes:
        if offset + size <= len(head):
            return head[offset : offset + size]
        if read_at is None:
            raise _Unreachable
        return read_at(offset, size)

    try:
        off = struct.unpack(e + "I", head[4:8])[0]
        n = struct.unpack(e + "H", get(off, 2))[0]
        table = get(off + 2, 12 * n)
        dims: dict[int, int] = {}
        for k in range(n):
            tag, typ, _count = struct.unpack(e + "HHI", table[12 * k : 12 * k + 8])
            raw = table[12 * k + 8 : 12 * k + 12]
            if tag in (256, 257):
                dims[tag] = struct.unpack(e + "H", raw[:2])[0] if typ == 3 else struct.unpack(e + "I", raw)[0]
        return (dims[256], dims[257]) if len(dims) == 2 else None
    except (struct.error, KeyError):
        return None


def _pnm(head: bytes) -> tuple[int, int] | None:
    if len(head) < 3 or head[:1] != b"P" or head[1:2] not in b"123456":
        return None
    fields: list[int] = []
    for line in head[2:].split(b"\n"):
        line = line.split(b"#")[0]
        for tok in line.split():
            if not tok.isdigit():
                return None
            fields.append(int(tok))
            if len(fields) == 2:
                return fields[0], fields[1]
    return None


def image_size_from_header(head: bytes, read_at: ReadAt | None = None) -> tuple[int, int] | None:
    """(width, height) from the first bytes of a PNG, JPEG, BMP, TIFF or PGM/PPM file; None if unknown.

    ``read_at`` reads further into the file for a TIFF whose directory is not in ``head``.
    """
    for parse in (_png, _jpeg, _bmp, _pnm):
        size = parse(head)
        if size is not None:
            return int(size[0]), int(size[1])
    size = _tiff(head, read_at)
    return None if size is None else (int(size[0]), int(size[1]))


def check_image_header(head: bytes, name: str, max_pixels: int = MAX_IMAGE_PIXELS, read_at: ReadAt | None = None
                       ) -> tuple[int, int] | None:
    """Refuse an image whose header declares more than ``max_pixels`` (or no pixels) before it is decoded.

    A TIFF whose directory cannot be reached (beyond ``head``, no ``read_at``) is refused: its size is unknown.
    """
    try:
        size = image_size_from_header(head, read_at)
    except _Unreachable:
        raise InputError(f"{name}: a TIFF whose image directory is past its first {len(head)} bytes, so its size "
                         "cannot be checked before decoding; convert it to PNG") from None
    if size is None:
        return None
    w, h = size
    if w <= 0 or h <= 0:
        raise InputError(f"{name}: the image header says {w}x{h} pixels; the file is damaged, replace it")
    if w * h > max_pixels:
        raise InputError(f"{name}: image is {w}x{h} ({w * h / 1e6:.0f} Mpx), over the {max_pixels / 1e6:.0f} Mpx "
                         "limit; use the camera's own images (downscale larger ones)")
    return size


def bytes_reader(data: bytes) -> ReadAt:
    """``read_at`` over bytes already in memory."""
    return lambda offset, size: data[offset : offset + size]
