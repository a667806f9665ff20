"""SDK pixel formats to 8-bit grey: mono shifted, a raw Bayer mosaic equalized without any interpolation."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.camera.detection import detect_chessboard
from lps_gui.camera.pixels import BayerGrey, to_grey8
from lps_gui.camera.render import BoardRenderer
from lps_gui.errors import HardwareError
from tests.capture.helpers import tiny_spec


def _board_image():
    rig = tiny_spec().rig
    renderer = BoardRenderer(rig.board, rig.intrinsics, 1.0, noise_grey=0.0)
    R, t = rig.camera_poses(__import__("lps_gui.core.truth.stage_errors", fromlist=["TruePose"]).TruePose(
        axis_mm=np.array([19.0]), straightness_um=np.zeros((1, 2)), angles_urad=np.zeros((1, 3))))
    return rig.board, renderer.render(R[0], t[0], np.random.default_rng(0))


def test_mono_formats_are_shifted_to_8_bits():
    data = np.array([[0, 4095], [2048, 16]], dtype=np.uint16)
    assert to_grey8(data, "Mono12").tolist() == [[0, 255], [128, 1]]
    assert to_grey8(data.astype(np.uint8), "Mono8").dtype == np.uint8
    with pytest.raises(HardwareError, match="pixel format YUV422"):
        to_grey8(data, "YUV422_8")


def test_a_bayer_mosaic_of_a_grey_board_gives_the_mono_corners_without_demosaic():
    board, grey = _board_image()
    gains = np.array([[0.55, 1.0], [1.0, 0.7]])  # R, G / G, B filter transmissions of an RG sensor
    mosaic = np.empty_like(grey)
    for i in (0, 1):
        for j in (0, 1):
            mosaic[i::2, j::2] = np.rint(grey[i::2, j::2] * gains[i, j]).astype(np.uint8)
    out = to_grey8(mosaic, "BayerRG8", BayerGrey())
    assert out.shape == grey.shape  # full resolution: corners in the mono camera's pixel coordinates
    mono, bayer = detect_chessboard(grey, board), detect_chessboard(out, board)
    assert mono is not None and bayer is not None
    # every pixel is its own sample brought back to the common level: no neighbour enters it
    bright = grey > 100
    scale = np.median(out[bright] / grey[bright])  # one common level for the four sub-lattices
    assert np.max(np.abs(out - scale * grey.astype(float))) <= 2.5  # the rounding of the darker filters
    assert np.max(np.abs(bayer - mono)) < 0.05


def test_bayer_gains_are_fixed_at_the_first_frame():
    conv = BayerGrey()
    rng = np.random.default_rng(1)
    first = (rng.random((8, 8)) * 200).astype(np.uint8)
    conv(first)
    gains = conv.gains.copy()
    conv((first // 2).astype(np.uint8))
    assert np.array_equal(conv.gains, gains)


def test_bayer_gains_multiply_the_full_depth_samples_before_the_8_bit_truncation():
    mosaic = np.full((4, 4), 31, np.uint16)  # 12-bit samples: 31 >> 4 is 1, 31 * 2 / 16 is 3.9
    conv = BayerGrey(np.array([[2.0, 1.0], [1.0, 1.0]]))
    out = to_grey8(mosaic, "BayerRG12", conv)
    assert out[0, 0] == 4 and out[0, 1] == 2  # truncating first gave 2 and 2: the gain lost its low bits


def test_sixteen_bit_colour_is_brought_to_8_bits():
    data = np.zeros((2, 2, 3), np.uint16)
    data[0, 0] = (65535, 65535, 65535)
    out = to_grey8(data, "RGB16Packed")
    assert out.dtype == np.uint8 and out[0, 0] == 255 and out[1, 1] == 0
