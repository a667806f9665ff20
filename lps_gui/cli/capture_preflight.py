"""``lps capture``'s checks that need no device: run before a session folder is created.

A refused command must leave nothing behind, or the retry meets "already holds
a session" (issue 13, item 8): the stage spec against the camera, the output
image format are checked first (the output folder itself is checked by
``Session.create`` / ``check_writable`` before they write).
"""
from __future__ import annotations

import argparse

from lps_gui.errors import InputError

SIM_STAGES = ("sim", "emulator")


def check_capture_args(args: argparse.Namespace, stage_spec: str, camera_spec: str) -> None:
    """Raise the one-line :class:`InputError` a later step would raise, before anything is written."""
    if camera_spec == "sim" and stage_spec not in SIM_STAGES and not stage_spec.startswith("grbl:"):
        raise InputError(f"--stage {stage_spec}: the simulated camera rides --stage sim, emulator or grbl:PORT (it "
                         f"renders where that stage reports); with a real camera give --camera N (and --board)")
    check_encode(args.encode)


def check_encode(ext: str) -> None:
    """The image format can be written (``cv2.imencode``), so the first frame will not fail on it."""
    import cv2
    import numpy as np

    from lps_gui.capture.engine import encode_image

    try:
        encode_image(np.zeros((2, 2), np.uint8), ext)
    except cv2.error:
        raise InputError(f"--encode {ext}: OpenCV has no encoder for it; use .png, .tif or .bmp") from None
