"""SDK pixel formats to the 8-bit grey frame detection uses, without a blurring colour conversion.

Mono formats are shifted down to 8 bits. A raw Bayer mosaic is not
demosaiced: a demosaic interpolates every missing colour sample from its
neighbours, which smooths the very edges the corner refinement fits. A
chessboard is grey (black and white), so the four 2x2 sub-lattices of the
mosaic see the same scene through different filter gains; equalizing those
four gains gives a full-resolution grey image in which every pixel is its
own measured sample (no interpolation, no loss of resolution, corners in the
same pixel coordinates as a mono camera). The gains are fixed at the first
frame (:class:`BayerGrey`), so they stay locked like exposure and gain.
"""
from __future__ import annotations

import re

import numpy as np

from lps_gui.errors import HardwareError

MONO = re.compile(r"^Mono(8|10|12|14|16)$")
BAYER = re.compile(r"^Bayer(RG|GB|GR|BG)(8|10|12|14|16)$")
COLOUR = {"RGB8": "rgb", "RGB8Packed": "rgb", "BGR8": "bgr", "BGR8Packed": "bgr", "RGBa8": "rgba", "BGRa8": "bgra",
          "BGRA8Packed": "bgra", "RGB16Packed": "rgb", "RGB16": "rgb"}
COLOUR_BITS = {"RGB16Packed": 16, "RGB16": 16}  # colour formats of more than 8 bits a sample
CHANNELS = {"rgb": 3, "bgr": 3, "rgba": 4, "bgra": 4}


def bits_of(pixel_format: str) -> int:
    """Bits per sample of a mono, Bayer or colour format (8 unless the name says more)."""
    m = MONO.match(pixel_format) or BAYER.match(pixel_format)
    return int(m.groups()[-1]) if m else COLOUR_BITS.get(pixel_format, 8)


def is_supported(pixel_format: str) -> bool:
    return bool(MONO.match(pixel_format) or BAYER.match(pixel_format) or pixel_format in COLOUR)


def to_8bit(data: np.ndarray, bits: int) -> np.ndarray:
    """Samples of ``bits`` bits (in uint8 or uint16) down to uint8 by a right shift."""
    if data.dtype == np.uint8 and bits == 8:
        return data
    return (data.astype(np.uint16) >> max(bits - 8, 0)).astype(np.uint8)


def colour_to_grey(data: np.ndarray, order: str) -> np.ndarray:
    """Per-pixel weighted sum (ITU-R BT.601, as OpenCV): no neighbourhood, no blur."""
    import cv2

    codes = {"rgb": cv2.COLOR_RGB2GRAY, "bgr": cv2.COLOR_BGR2GRAY, "rgba": cv2.COLOR_RGBA2GRAY, "bgra": cv2.COLOR_BGRA2GRAY}
    return cv2.cvtColor(np.ascontiguousarray(data), codes[order])


class BayerGrey:
    """A raw mosaic as grey: each 2x2 sub-lattice scaled to the common level; gains fixed at the first frame.

    The gains multiply the samples at their full depth (10 to 16 bits) before the result is brought to
    8 bits: truncating first would throw away the low bits the gain brings up. The gains are ratios of
    levels, so the same gains serve every bit depth; a session records them and a resumed capture reuses them.
    """

    def __init__(self, gains: np.ndarray | None = None) -> None:
        self.gains = None if gains is None else np.asarray(gains, dtype=np.float32).reshape(2, 2)

    @staticmethod
    def estimate_gains(mosaic: np.ndarray) -> np.ndarray:
        """Gains (2, 2) bringing each sub-lattice's bright level (99th percentile: the white squares) to their mean."""
        levels = np.array([[np.percentile(mosaic[i::2, j::2], 99.0) for j in (0, 1)] for i in (0, 1)], dtype=np.float64)
        levels = np.maximum(levels, 1.0)
        return (levels.mean() / levels).astype(np.float32)

    def __call__(self, mosaic: np.ndarray, bits: int = 8) -> np.ndarray:
        if self.gains is None:
            self.gains = self.estimate_gains(mosaic)
        h, w = mosaic.shape
        out = mosaic.astype(np.float32)
        for i in (0, 1):
            for j in (0, 1):
                out[i::2, j::2] *= self.gains[i, j]
        if bits > 8:
            out *= np.float32(2.0 ** (8 - bits))
        return np.clip(np.rint(out), 0, 255).astype(np.uint8).reshape(h, w)


def to_grey8(data: np.ndarray, pixel_format: str, bayer: BayerGrey | None = None) -> np.ndarray:
    """The 8-bit grey (H, W) frame of an SDK buffer in ``pixel_format``; HardwareError for formats not handled."""
    if MONO.match(pixel_format):
        return to_8bit(data.reshape(data.shape[:2]), bits_of(pixel_format))
    if BAYER.match(pixel_format):
        return (bayer or BayerGrey())(data.reshape(data.shape[:2]), bits_of(pixel_format))
    if pixel_format in COLOUR:
        return to_8bit(colour_to_grey(data, COLOUR[pixel_format]), bits_of(pixel_format))
    raise HardwareError(
        f"camera: pixel format {pixel_format} is not handled; set PixelFormat to Mono8..Mono16, Bayer..8..16, RGB8 or BGR8"
    )
