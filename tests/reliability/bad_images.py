"""Small files that declare huge or misleading images: each is a few bytes to a few KB on disk.

Built by hand (struct), so each header field is the one named; the decoders
would allocate the declared size (or decode a raw file's preview) if nothing
checked the header first.
"""
from __future__ import annotations

import struct

import cv2
import numpy as np


def tiff(entries: list[tuple[int, int, int, int]], data: bytes = b"", big_endian: bool = False) -> bytes:
    """A one-directory TIFF: ``entries`` are (tag, type, count, value), the pixel data after the directory."""
    e = ">" if big_endian else "<"
    n = len(entries)
    data_off = 8 + 2 + 12 * n + 4
    out = bytearray((b"MM\x00*" if big_endian else b"II*\x00") + struct.pack(e + "I", 8) + struct.pack(e + "H", n))
    for tag, typ, count, value in entries:
        value = data_off if value == -1 else value
        field = struct.pack(e + "HH", value, 0) if typ == 3 else struct.pack(e + "I", value)
        out += struct.pack(e + "HHI", tag, typ, count) + field
    return bytes(out + struct.pack(e + "I", 0) + data)


def grey_tiff(w: int, h: int, extra: list[tuple[int, int, int, int]] = ()) -> bytes:
    """An uncompressed 8-bit grey TIFF OpenCV decodes, with ``extra`` directory entries."""
    entries = sorted([(256, 3, 1, w), (257, 3, 1, h), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1),
                      (273, 4, 1, -1), (277, 3, 1, 1), (278, 3, 1, h), (279, 4, 1, w * h), *extra])
    return tiff(entries, bytes(np.full(w * h, 128, np.uint8)))


def nef_like() -> bytes:
    """A raw file's layout: IFD0 a 160x120 preview (NewSubfileType 1), the raw data behind SubIFDs."""
    return grey_tiff(160, 120, [(254, 4, 1, 1), (330, 4, 1, 8)])


def dng_like() -> bytes:
    """A DNG's IFD0: the full-size flag clear but DNGVersion present."""
    return grey_tiff(160, 120, [(50706, 1, 4, 0x00000401)])


def duplicated_size_tiff() -> bytes:
    """The width tag twice: 16 px for the header reader, 30000 for a decoder that takes the last."""
    return grey_tiff(16, 16, [(256, 3, 1, 30000)])


def bigtiff() -> bytes:
    return b"II+\x00\x08\x00\x00\x00" + struct.pack("<Q", 16) + b"\x00" * 64


def gif_bomb() -> bytes:
    """35 bytes declaring a 30000x30000 screen and image."""
    return (b"GIF89a" + struct.pack("<HH", 30000, 30000) + b"\x00\x00\x00" + b","
            + struct.pack("<HHHH", 0, 0, 30000, 30000) + b"\x00\x02\x02\x44\x01\x00;")


def hdr_bomb() -> bytes:
    return b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 30000 +X 30000\n" + b"\x00" * 64


def webp_bomb() -> bytes:
    """A lossless WebP header declaring 16384x16384 (268 Mpx)."""
    bits = (16383) | (16383 << 14)
    payload = b"\x2f" + bits.to_bytes(4, "little") + b"\x00" * 16
    chunk = b"VP8L" + struct.pack("<I", len(payload)) + payload
    return b"RIFF" + struct.pack("<I", 4 + len(chunk)) + b"WEBP" + chunk


def jpeg_with_sof_after(comment_bytes: int, w: int, h: int) -> bytes:
    """A real small JPEG whose frame header follows comments of ``comment_bytes``, its size fields set to w x h."""
    ok, buf = cv2.imencode(".jpg", np.full((8, 8), 128, np.uint8))
    data = bytearray(buf.tobytes())
    i = 2
    while not (data[i] == 0xFF and 0xC0 <= data[i + 1] <= 0xC2):
        i += 2 + struct.unpack(">H", data[i + 2:i + 4])[0]
    data[i + 5:i + 9] = struct.pack(">HH", h, w)
    comments = b""
    while len(comments) < comment_bytes:
        comments += b"\xff\xfe" + struct.pack(">H", 65000) + b"x" * 64998
    return bytes(data[:2] + comments + data[2:])
