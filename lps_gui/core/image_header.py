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


def _jpeg(head: bytes, read_at: "ReadAt | None" = None) -> tuple[int, int] | None:
    """Width and height from the frame header (SOF), found by walking the segments wherever in the file it is.

    A 70 KB comment or EXIF block puts the SOF past the first 64 KB: ``read_at`` fetches it; without one (or
    with no SOF before the scan) the size is unknown and the caller refuses the file.
    """
    if head[:2] != b"\xff\xd8":
        return None
    get = _reader(head, read_at, "JPEG")
    i = 2
    for _ in range(1 << 16):  # segments are at least 4 bytes long: a bounded walk
        seg = get(i, 9)
        if len(seg) < 4:
            return None
        if seg[0] != 0xFF:
            i += 1
            continue
        marker = seg[1]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7 or marker == 0xFF:
            i += 1 if marker == 0xFF else 2
            continue
        if marker in (0xD9, 0xDA):  # end of image, start of scan: no frame header before the data
            return None
        length = struct.unpack(">H", seg[2:4])[0]
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            if len(seg) < 9:
                return None
            h, w = struct.unpack(">HH", seg[5:9])
            return w, h
        i += 2 + length
    return None


def _reader(head: bytes, read_at: "ReadAt | None", fmt: str) -> "ReadAt":
    """Bytes at an offset: from ``head`` when there, else through ``read_at`` (none: the field is unreachable)."""

    def get(offset: int, size: int) -> bytes:
        if offset + size <= len(head):
            return head[offset : offset + size]
        if read_at is None:
            raise _Unreachable(fmt)
        return read_at(offset, size)

    return get


def _webp(head: bytes) -> tuple[int, int] | None:
    """Canvas size of a lossy (VP8), lossless (VP8L) or extended (VP8X) WebP."""
    if head[:4] != b"RIFF" or head[8:12] != b"WEBP" or len(head) < 30:
        return None
    kind = head[12:16]
    if kind == b"VP8 " and head[23:26] == b"\x9d\x01\x2a":
        w, h = struct.unpack("<HH", head[26:30])
        return w & 0x3FFF, h & 0x3FFF
    if kind == b"VP8L" and head[20] == 0x2F:
        bits = int.from_bytes(head[21:25], "little")
        return (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1
    if kind == b"VP8X":
        return int.from_bytes(head[24:27], "little") + 1, int.from_bytes(head[27:30], "little") + 1
    return (0, 0)  # a WebP of another kind: refused as damaged


ReadAt = Callable[[int, int], bytes]  # (offset, size) -> the bytes of the file there (fewer at its end)


class _Unreachable(Exception):
    """The size field lies beyond the bytes given and no ``read_at`` can fetch it (args: the format)."""


def _tiff(head: bytes, read_at: ReadAt | None = None) -> tuple[int, int] | None:
    """Width and height from the first image directory (IFD), wherever in the file it is.

    OpenCV writes the IFD after the image data, so for anything but a tiny image it is not in the first
    64 KB: ``read_at`` fetches it (the caller has the file or its bytes); without one the TIFF is unreachable.
    """
    if head[:4] in (b"II+\x00", b"MM\x00+"):
        raise _Refused("a BigTIFF, whose size cannot be checked before decoding; convert it to PNG")
    if head[:4] not in (b"II*\x00", b"MM\x00*"):
        return None
    e = "<" if head[:2] == b"II" else ">"
    get = _reader(head, read_at, "TIFF")

    if head[8:10] == b"CR":
        raise _Refused(RAW_REFUSAL)
    try:
        off = struct.unpack(e + "I", head[4:8])[0]
        n = struct.unpack(e + "H", get(off, 2))[0]
        table = get(off + 2, 12 * n)
        dims: dict[int, int] = {}
        tags: list[int] = []
        subfile = 0
        for k in range(n):
            tag, typ, _count = struct.unpack(e + "HHI", table[12 * k : 12 * k + 8])
            raw = table[12 * k + 8 : 12 * k + 12]
            tags.append(tag)
            value = struct.unpack(e + "H", raw[:2])[0] if typ == 3 else struct.unpack(e + "I", raw)[0]
            if tag in (256, 257):
                dims[tag] = value
            elif tag == 254:
                subfile = value
    except struct.error:
        return None
    if len(tags) != len(set(tags)):
        raise _Refused("a TIFF with a tag repeated in its image directory (which one counts is the decoder's "
                       "guess); re-save it as PNG")
    if subfile & 1 or RAW_TAGS & set(tags):
        raise _Refused(RAW_REFUSAL)
    return (dims[256], dims[257]) if len(dims) == 2 else None


RAW_TAGS = {330, 50706}  # SubIFDs (the full-size raw data lies there), DNGVersion
RAW_REFUSAL = ("a camera raw file (NEF, DNG, CR2, ARW... are TIFF-based): OpenCV would decode only its small "
               "preview; export it as 16-bit TIFF or PNG, or set the camera to JPEG or TIFF")


class _Refused(Exception):
    """A file whose format is recognized and refused (args: why, and what to do)."""


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
    """(width, height) from the first bytes of a PNG, JPEG, BMP, TIFF, PGM/PPM or WebP file; None if unknown.

    ``read_at`` reads further into the file for a TIFF whose directory or a JPEG whose frame header is not in ``head``.
    """
    for parse in (_png, _bmp, _pnm, _webp):
        size = parse(head)
        if size is not None:
            return int(size[0]), int(size[1])
    size = _jpeg(head, read_at) or _tiff(head, read_at)
    return None if size is None else (int(size[0]), int(size[1]))


FORMATS = "PNG, TIFF, BMP, PGM/PPM, JPEG or WebP"


def check_image_header(head: bytes, name: str, max_pixels: int = MAX_IMAGE_PIXELS, read_at: ReadAt | None = None
                       ) -> tuple[int, int] | None:
    """Refuse an image whose header declares more than ``max_pixels`` (or no pixels) before it is decoded.

    Only formats whose size is read here get to the decoder: GIF, Radiance HDR, OpenEXR, JPEG 2000 and the
    rest OpenCV also decodes would reach it unchecked (a 35-byte GIF declaring 30000x30000 took 23 GB), so
    they are refused, as are a TIFF whose directory or a JPEG whose frame header cannot be reached (beyond
    ``head``, no ``read_at``), a BigTIFF, a TIFF with repeated tags and a TIFF-based camera raw file.
    Empty bytes pass (None): the caller's decoder says the file is empty or truncated.
    """
    if not head:
        return None
    try:
        size = image_size_from_header(head, read_at)
    except _Unreachable as exc:
        raise InputError(f"{name}: a {exc.args[0]} whose size field is past its first {len(head)} bytes, so its size "
                         "cannot be checked before decoding; convert it to PNG") from None
    except _Refused as exc:
        raise InputError(f"{name}: {exc.args[0]}") from None
    if size is None:
        raise InputError(f"{name}: not a {FORMATS} image whose size can be checked before decoding (or damaged); "
                         "convert it to PNG")
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
