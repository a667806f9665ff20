"""Issue 39's independent bad-input campaign: each case it found, reproduced and answered with one line.

The cases that would exhaust memory on a reader without the check are tested
at the header check itself (what every image reader calls before decoding),
so the test fails on such a reader without the machine paying for it.
"""
from __future__ import annotations

import pytest

from lps_gui.core.image_header import bytes_reader, check_image_header
from lps_gui.errors import HardwareError, InputError
from lps_gui.io.image_file import decode_image
from tests.reliability import bad_images


def _check(data: bytes, name: str = "x"):
    return check_image_header(data[:1 << 16], name, read_at=bytes_reader(data))


@pytest.mark.parametrize("make,needle", [
    (bad_images.gif_bomb, "not a PNG, TIFF, BMP, PGM/PPM, JPEG or WebP image"),
    (bad_images.hdr_bomb, "not a PNG, TIFF, BMP, PGM/PPM, JPEG or WebP image"),
    (bad_images.webp_bomb, r"16384x16384 \(268 Mpx\), over the 100 Mpx limit"),
    (lambda: bad_images.jpeg_with_sof_after(70_000, 30000, 30000), r"30000x30000 \(900 Mpx\), over the 100 Mpx limit"),
    (bad_images.bigtiff, "a BigTIFF"),
    (bad_images.duplicated_size_tiff, "a tag repeated in its image directory"),
])
def test_every_format_opencv_decodes_is_size_checked_or_refused_before_decoding(make, needle):
    with pytest.raises(InputError, match=needle) as exc:
        _check(make(), "v.img")
    assert str(exc.value).startswith("v.img: ") and "\n" not in str(exc.value)


def test_a_jpeg_whose_frame_header_follows_a_70_kb_comment_is_read_at_its_size():
    data = bad_images.jpeg_with_sof_after(70_000, 8, 8)
    assert _check(data) == (8, 8)
    assert decode_image(data, "c.jpg").shape == (8, 8)
    with pytest.raises(InputError, match="past its first 65536 bytes"):  # a reader that cannot reach it refuses
        check_image_header(data[:1 << 16], "c.jpg")


@pytest.mark.parametrize("make", [bad_images.nef_like, bad_images.dng_like])
def test_a_tiff_based_raw_file_is_refused_not_decoded_as_its_preview(make):
    with pytest.raises(InputError, match=r"^DSC_0001.NEF: a camera raw file \(NEF, DNG, CR2, ARW"):
        decode_image(make(), "DSC_0001.NEF")


def test_a_tethered_camera_delivering_a_raw_file_pauses_with_one_line():
    from lps_gui.camera.gphoto2_camera import decode

    with pytest.raises(HardwareError, match=r"^camera gphoto2:: DSC_0001.NEF: a camera raw file .*, then resume$"):
        decode(bad_images.nef_like(), "camera gphoto2:: DSC_0001.NEF")
