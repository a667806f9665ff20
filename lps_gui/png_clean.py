"""A PNG reduced to what decoding needs, its damage found before libpng sees it.

libpng prints its warnings and errors ("libpng warning: iCCP: too short",
"libpng error: IDAT: CRC error") with fprintf to the process's stderr, and
OpenCV installs no handler that stops it: a damaged or merely unusual file
put lines on the console beside lps's own one-line message. The decoder is
therefore given only the chunks it needs (IHDR, PLTE, tRNS, IDAT, IEND),
each checked against its CRC, with a zlib stream that inflates to exactly the
image's filtered rows, each starting with a valid filter byte; what fails is
an InputError naming the file. Ancillary chunks (text, colour profiles,
gamma, times) are dropped: OpenCV uses none of them. Pure bytes in, bytes out,
and layer-neutral (like file_limits.py): ``io`` decodes session images and
``camera`` decodes a replayed folder's and a tethered camera's files.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np

from lps_gui.errors import InputError

SIGNATURE = b"\x89PNG\r\n\x1a\n"
_DEPTHS = {0: (1, 2, 4, 8, 16), 2: (8, 16), 3: (1, 2, 4, 8), 4: (8, 16), 6: (8, 16)}  # colour type: bit depths
_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
_ADAM7 = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))
_USER_MAX = 1_000_000  # libpng's default width and height limit (PNG_USER_WIDTH_MAX): over it, it errors on stderr
_PIECE = 1 << 20  # inflated bytes per step: the check holds one piece, never the image


def clean_png(data: bytes, name: str) -> bytes:
    """``data`` itself when it is no PNG; else the PNG rebuilt from its checked critical chunks.

    Raises InputError (``name``: what is wrong, what to do) for a damaged PNG:
    a chunk failing its CRC, a truncated file, image data that does not
    inflate to the image's rows, an IHDR libpng refuses.
    """
    if not data.startswith(SIGNATURE):
        return data
    chunks = _chunks(data, name)
    if not chunks or chunks[0][0] != b"IHDR" or len(chunks[0][1]) != 13:
        raise _damaged(name, "does not begin with its IHDR header chunk")
    w, h, depth, ctype, compression, filtering, interlace = struct.unpack(">IIBBBBB", chunks[0][1])
    if depth not in _DEPTHS.get(ctype, ()) or compression or filtering or interlace > 1 or not (0 < w and 0 < h):
        raise _damaged(name, f"has an invalid IHDR (colour type {ctype}, bit depth {depth})")
    if w > _USER_MAX or h > _USER_MAX:
        raise InputError(f"{name}: a {w}x{h} PNG, over the {_USER_MAX} pixels a side PNG decoding takes; "
                         "save the image at a usual size")
    plte = next((body for kind, body in chunks if kind == b"PLTE"), None)
    trns = next((body for kind, body in chunks if kind == b"tRNS"), None)
    out = [_chunk(b"IHDR", chunks[0][1])]
    if ctype == 3:
        if plte is None or not plte or len(plte) % 3 or len(plte) > 3 * 256:
            raise _damaged(name, "is a palette image without a valid palette (PLTE)")
        entries = 1 << depth  # every index the bit depth can hold is in the palette: no "index exceeding" warning
        out.append(_chunk(b"PLTE", plte + bytes(max(0, 3 * entries - len(plte)))))
        if trns is not None and len(trns) <= max(entries, len(plte) // 3):
            out.append(_chunk(b"tRNS", trns))
    elif trns is not None and ctype in (0, 2) and len(trns) == 2 * _CHANNELS[ctype] and \
            max(struct.unpack(f">{_CHANNELS[ctype]}H", trns)) < 1 << depth:
        out.append(_chunk(b"tRNS", trns))
    stream = b"".join(body for kind, body in chunks if kind == b"IDAT")
    used = _check_stream(stream, _rows(w, h, depth * _CHANNELS[ctype], interlace), name)
    out.append(_chunk(b"IDAT", stream[:used]))
    out.append(_chunk(b"IEND", b""))
    return SIGNATURE + b"".join(out)


def _damaged(name: str, what: str) -> InputError:
    return InputError(f"{name}: a damaged PNG ({what}); copy or capture the image again")


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _chunks(data: bytes, name: str) -> list[tuple[bytes, bytes]]:
    """The (type, body) of the chunks decoding needs, up to IEND, CRC-checked; unknown critical chunks refused."""
    kept: list[tuple[bytes, bytes]] = []
    pos, n, last = len(SIGNATURE), len(data), b""
    while True:
        if pos + 12 > n:
            if any(k == b"IDAT" for k, _ in kept):
                return kept  # no IEND: the stream check below says whether the image data is whole
            raise _damaged(name, f"ends at byte {n} inside its chunks: truncated")
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        end = pos + 12 + length
        if not kind.isalpha() or not kind.isascii():
            raise _damaged(name, f"a chunk at byte {pos} has no valid type")
        if end > n:
            raise _damaged(name, f"its {kind.decode()} chunk at byte {pos} runs past the end of the file: truncated")
        critical = not kind[0] & 0x20
        if kind in (b"IHDR", b"PLTE", b"tRNS", b"IDAT", b"IEND"):
            body = data[pos + 8:end - 4]
            if zlib.crc32(kind + body) != struct.unpack(">I", data[end - 4:end])[0]:
                raise _damaged(name, f"its {kind.decode()} chunk at byte {pos} fails its CRC check")
            if kind == b"IEND":
                return kept
            if kind == b"IDAT" and any(k == b"IDAT" for k, _ in kept) and last != b"IDAT":
                raise _damaged(name, f"its image data (IDAT) is split by a {last.decode()} chunk")
            if kind != b"IDAT" and any(k == kind for k, _ in kept):
                raise _damaged(name, f"it has two {kind.decode()} chunks")
            kept.append((kind, body))
        elif critical:
            raise InputError(f"{name}: a PNG with a critical chunk {kind.decode()!r} no decoder here knows; save it as "
                             "a plain PNG")
        last, pos = kind, end


def _rows(w: int, h: int, bits_per_pixel: int, interlace: int) -> list[tuple[int, int, int]]:
    """(start, rows, stride) of each run of filtered rows in the inflated data (one run, or one per Adam7 pass)."""
    runs, start = [], 0
    for x0, y0, dx, dy in _ADAM7 if interlace else ((0, 0, 1, 1),):
        pw, ph = (w - x0 + dx - 1) // dx, (h - y0 + dy - 1) // dy
        if pw > 0 and ph > 0:
            stride = 1 + (pw * bits_per_pixel + 7) // 8
            runs.append((start, ph, stride))
            start += ph * stride
    return runs


def _check_stream(stream: bytes, runs: list[tuple[int, int, int]], name: str) -> int:
    """How many bytes of ``stream`` the zlib data takes; InputError unless it inflates to exactly the rows of
    ``runs`` with a filter byte of 0-4 at each row's start (libpng's "bad adaptive filter value")."""
    total = runs[-1][0] + runs[-1][1] * runs[-1][2]
    inflate = zlib.decompressobj()
    pos, rest = 0, stream
    try:
        while not inflate.eof:
            piece = inflate.decompress(rest, _PIECE)
            rest = inflate.unconsumed_tail
            if pos + len(piece) > total:
                raise _damaged(name, "more image data than its size holds")
            _check_filters(np.frombuffer(piece, np.uint8), pos, runs, name)
            pos += len(piece)
            if not piece and not rest:
                break
    except zlib.error as exc:
        raise _damaged(name, f"its image data does not inflate: {exc}") from None
    if not inflate.eof or pos != total:
        raise _damaged(name, f"its image data ends after {pos} of {total} bytes: truncated")
    return len(stream) - len(inflate.unused_data)


def _check_filters(piece: np.ndarray, pos: int, runs: list[tuple[int, int, int]], name: str) -> None:
    """InputError if a row of ``runs`` starting in ``piece`` (at ``pos`` of the inflated data) has a bad filter byte."""
    for start, rows, stride in runs:
        first = max(0, -(-(pos - start) // stride))  # the first row starting at or after pos
        last = min(rows, -(-(pos + len(piece) - start) // stride))  # rows starting before the piece ends
        if first < last:
            at = start + np.arange(first, last) * stride - pos
            if (piece[at] > 4).any():
                raise _damaged(name, "a row of its image data has an invalid filter type")
