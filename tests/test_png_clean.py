"""PNGs rebuilt from their checked critical chunks decode to the same pixels, and libpng never gets to print.

libpng writes its warnings and errors to file descriptor 2 itself (capfd sees them, capsys would not).
"""
from __future__ import annotations

import struct
import zlib

import cv2
import numpy as np
import pytest

from lps_gui.png_clean import SIGNATURE, _ADAM7, clean_png
from lps_gui.errors import InputError
from lps_gui.io.image_file import decode_image

RNG = np.random.default_rng(39)


def _chunk(kind: bytes, body: bytes, crc: int | None = None) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) if crc is None else crc)


def _png(raw_rows: bytes, w: int, h: int, depth: int, ctype: int, interlace: int = 0, before_idat: bytes = b"") -> bytes:
    ihdr = struct.pack(">IIBBBBB", w, h, depth, ctype, 0, 0, interlace)
    return SIGNATURE + _chunk(b"IHDR", ihdr) + before_idat + _chunk(b"IDAT", zlib.compress(raw_rows)) + _chunk(b"IEND", b"")


def _rows(img: np.ndarray, filt: int = 0) -> bytes:
    """Filter type 0 (or 1, Sub, for 8-bit grey) rows of a (H, W[, C]) big-endian image."""
    flat = img.reshape(img.shape[0], -1)
    if filt == 1:
        flat = np.diff(flat.astype(np.int16), axis=1, prepend=0).astype(np.uint8)
    return b"".join(bytes([filt]) + row.tobytes() for row in flat)


def _adam7(img: np.ndarray) -> bytes:
    return b"".join(_rows(img[y0::dy, x0::dx]) for x0, y0, dx, dy in _ADAM7
                    if img[y0::dy, x0::dx].size)


def _encoded(img: np.ndarray) -> bytes:
    return bytes(cv2.imencode(".png", img)[1])


def _same(data: bytes, flags: int) -> None:
    want = cv2.imdecode(np.frombuffer(data, np.uint8), flags)
    got = cv2.imdecode(np.frombuffer(clean_png(data, "x.png"), np.uint8), flags)
    assert got.dtype == want.dtype and np.array_equal(got, want)


@pytest.mark.parametrize("img", [
    RNG.integers(0, 256, (37, 53), dtype=np.uint8),
    RNG.integers(0, 65536, (37, 53), dtype=np.uint16),
    RNG.integers(0, 256, (21, 17, 3), dtype=np.uint8),
    RNG.integers(0, 256, (21, 17, 4), dtype=np.uint8),
    RNG.integers(0, 65536, (9, 11, 3), dtype=np.uint16),
], ids=["grey8", "grey16", "bgr8", "bgra8", "bgr16"])
@pytest.mark.parametrize("flags", [cv2.IMREAD_GRAYSCALE, cv2.IMREAD_UNCHANGED])
def test_opencv_encoded_pngs_decode_to_the_same_pixels(img, flags):
    _same(_encoded(img), flags)


@pytest.mark.parametrize("w,h", [(1, 1), (13, 7), (8, 8), (3, 30)])
def test_interlaced_pngs_decode_to_their_pixels(w, h):
    grey = RNG.integers(0, 256, (h, w), dtype=np.uint8)
    data = _png(_adam7(grey), w, h, 8, 0, interlace=1)
    assert np.array_equal(decode_image(data, "i.png"), grey)
    rgb = RNG.integers(0, 65536, (h, w, 3), dtype=np.uint16)
    data = _png(_adam7(rgb.astype(">u2")), w, h, 16, 2, interlace=1)
    assert np.array_equal(decode_image(data, "i.png", cv2.IMREAD_UNCHANGED), rgb[..., ::-1])


def test_palette_and_low_bit_depth_pngs_decode_to_their_pixels():
    idx = RNG.integers(0, 3, (10, 16), dtype=np.uint8)  # indices 0-2 of a 3-entry palette, 4 bits a pixel
    packed = (idx[:, 0::2] << 4 | idx[:, 1::2]).astype(np.uint8)
    palette = bytes([10, 20, 30, 200, 100, 50, 0, 255, 0])
    data = _png(_rows(packed), 16, 10, 4, 3, before_idat=_chunk(b"PLTE", palette) + _chunk(b"tRNS", b"\xff\x80"))
    for flags in (cv2.IMREAD_GRAYSCALE, cv2.IMREAD_UNCHANGED, cv2.IMREAD_COLOR):
        _same(data, flags)
    bgr = decode_image(data, "p.png", cv2.IMREAD_COLOR)
    assert np.array_equal(bgr, np.frombuffer(palette, np.uint8).reshape(3, 3)[idx][..., ::-1])
    bits = RNG.integers(0, 2, (5, 19), dtype=np.uint8)
    packed = np.packbits(bits, axis=1)
    assert np.array_equal(decode_image(_png(_rows(packed), 19, 5, 1, 0), "b.png"), bits * 255)
    grey = RNG.integers(0, 256, (6, 9), dtype=np.uint8)
    assert np.array_equal(decode_image(_png(_rows(grey, filt=1), 9, 6, 8, 0), "s.png"), grey)  # Sub filter rows


def _after_ihdr(data: bytes, extra: bytes) -> bytes:
    return data[:33] + extra + data[33:]


@pytest.mark.parametrize("extra", [
    _chunk(b"tEXt", b"a\x00b", crc=1),  # "libpng warning: tEXt: CRC error"
    _chunk(b"iCCP", b"prof\x00\x00" + zlib.compress(b"x" * 200)),  # "libpng warning: iCCP: too short"
    _chunk(b"gAMA", b"\x00"),  # "libpng warning: gAMA: invalid"
    _chunk(b"tRNS", b"\x00\x01\x02"),  # "libpng warning: tRNS: invalid" (grey needs 2 bytes)
], ids=["bad-crc-text", "short-iccp", "short-gama", "bad-trns"])
def test_ancillary_chunks_libpng_warns_about_never_reach_stderr(capfd, extra):
    grey = RNG.integers(0, 256, (12, 10), dtype=np.uint8)
    data = _after_ihdr(_encoded(grey), extra)
    capfd.readouterr()
    assert np.array_equal(decode_image(data, "w.png"), grey)
    assert capfd.readouterr().err == ""


def _idat_at(data: bytes) -> int:
    return data.index(b"IDAT") - 4


def _damage(data: bytes, how: str) -> bytes:
    i = _idat_at(data)
    n = struct.unpack(">I", data[i:i + 4])[0]
    if how == "idat-crc":
        return data[:i + 8 + n] + b"\0\0\0\0" + data[i + 12 + n:]
    if how == "truncated":
        return data[:i + 8 + n // 2]
    if how == "no-iend":
        return data[:i + 12 + n]
    body = bytearray(zlib.decompress(data[i + 8:i + 8 + n]))
    if how == "filter":
        body[0] = 9
    elif how == "short-stream":
        body = body[:-5]
    elif how == "long-stream":
        body += b"\0" * 11
    return data[:i] + _chunk(b"IDAT", zlib.compress(bytes(body))) + data[i + 12 + n:]


@pytest.mark.parametrize("how,says", [
    ("idat-crc", r"its IDAT chunk at byte 33 fails its CRC check"),
    ("truncated", r"its IDAT chunk at byte 33 runs past the end of the file: truncated"),
    ("filter", r"a row of its image data has an invalid filter type"),
    ("short-stream", r"its image data ends after 115 of 120 bytes: truncated"),
    ("long-stream", r"more image data than its size holds"),
])
def test_a_damaged_png_is_one_line_and_libpng_says_nothing(capfd, how, says):
    data = _damage(_encoded(RNG.integers(0, 256, (12, 9), dtype=np.uint8)), how)
    capfd.readouterr()
    with pytest.raises(InputError, match=rf"^d.png: a damaged PNG \({says}\); copy or capture the image again$"):
        decode_image(data, "d.png")
    assert capfd.readouterr().err == ""


def test_a_png_without_its_end_chunk_decodes_when_its_image_data_is_whole(capfd):
    grey = RNG.integers(0, 256, (12, 9), dtype=np.uint8)
    capfd.readouterr()
    assert np.array_equal(decode_image(_damage(_encoded(grey), "no-iend"), "e.png"), grey)
    assert capfd.readouterr().err == ""


def test_an_unknown_critical_chunk_is_refused_and_other_files_pass_untouched():
    data = _after_ihdr(_encoded(np.zeros((4, 4), np.uint8)), _chunk(b"ABCD", b"x"))
    with pytest.raises(InputError, match=r"^c.png: a PNG with a critical chunk 'ABCD' no decoder here knows"):
        clean_png(data, "c.png")
    jpeg = bytes(cv2.imencode(".jpg", np.zeros((4, 4), np.uint8))[1])
    assert clean_png(jpeg, "c.jpg") is jpeg


def test_the_camera_paths_decode_through_the_same_check(tmp_path, capfd):
    from lps_gui.camera.folder_replay import _read_checked
    from lps_gui.camera.gphoto2_camera import decode
    from lps_gui.errors import HardwareError

    grey = RNG.integers(0, 256, (12, 10), dtype=np.uint8)
    warned = _after_ihdr(_encoded(grey), _chunk(b"tEXt", b"a\x00b", crc=1))
    (tmp_path / "w.png").write_bytes(warned)
    capfd.readouterr()
    assert np.array_equal(_read_checked(tmp_path / "w.png"), grey)
    assert np.array_equal(decode(warned, "camera gphoto2:: w.png"), grey)
    with pytest.raises(HardwareError, match=r"^camera gphoto2:: d.png: a damaged PNG \(its IDAT chunk at byte 33 "):
        decode(_damage(_encoded(grey), "idat-crc"), "camera gphoto2:: d.png")
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("ext", [".bmp", ".pgm"])
def test_opencvs_own_error_lines_for_a_truncated_image_never_reach_stderr(capfd, ext):
    """OpenCV logs "[ERROR:0@0.9] global loadsave.cpp ... Unexpected end of input stream" at its default level."""
    import cv2.utils.logging as cv_log

    data = bytes(cv2.imencode(ext, RNG.integers(0, 256, (64, 80), dtype=np.uint8))[1])
    level = cv_log.getLogLevel()
    capfd.readouterr()
    assert decode_image(data[:len(data) * 2 // 3], "t" + ext) is None  # read_image turns it into its one line
    assert capfd.readouterr().err == ""
    assert cv_log.getLogLevel() == level  # put back: other OpenCV errors are still logged


def test_overlapping_decodes_on_threads_put_the_log_level_back_once():
    import threading

    import cv2.utils.logging as cv_log

    from lps_gui.quiet_decode import opencv_log_silenced

    level = cv_log.getLogLevel()
    inside, go = threading.Event(), threading.Event()

    def other():
        with opencv_log_silenced():
            inside.set()
            go.wait(30)

    t = threading.Thread(target=other)
    t.start()
    try:
        assert inside.wait(30)
        with opencv_log_silenced():
            assert cv_log.getLogLevel() == cv_log.LOG_LEVEL_SILENT
        assert cv_log.getLogLevel() == cv_log.LOG_LEVEL_SILENT  # the other decode is still under way
    finally:
        go.set()
        t.join(30)
    assert cv_log.getLogLevel() == level
