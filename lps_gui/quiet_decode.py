"""``cv2.imdecode`` with the decoders' own lines kept off stderr: lps says what is wrong with a file in one line.

Two sources print while OpenCV decodes: OpenCV's log ("[ERROR:0@0.9] global
loadsave.cpp ... can't read data: ... Unexpected end of input stream" for a
truncated BMP or PGM, "[ WARN:0@0.4] global grfmt_tiff.cpp ..." for an odd
TIFF), silenced for the length of each decode and put back after (a lock and
a count, so overlapping decodes on threads restore it once); and libpng,
which writes to file descriptor 2 itself and is given only checked critical
chunks (:func:`lps_gui.png_clean.clean_png`). Layer-neutral like file_limits:
``io`` decodes session images, ``camera`` a replayed folder's and a tethered
camera's files.
"""
from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Iterator

import cv2
import numpy as np

from lps_gui.png_clean import clean_png

_lock = threading.Lock()
_quiet = [0, 0]  # decodes under way, the log level to put back when the last ends


@contextmanager
def opencv_log_silenced() -> Iterator[None]:
    """OpenCV's log silent while the block runs (its errors still raise, a failed decode still returns None)."""
    import cv2.utils.logging as cv_log

    with _lock:
        if _quiet[0] == 0:
            _quiet[1] = cv_log.getLogLevel()
            cv_log.setLogLevel(cv_log.LOG_LEVEL_SILENT)
        _quiet[0] += 1
    try:
        yield
    finally:
        with _lock:
            _quiet[0] -= 1
            if _quiet[0] == 0:
                cv_log.setLogLevel(_quiet[1])


def imdecode_quiet(data: bytes, name: str, flags: int) -> np.ndarray | None:
    """``cv2.imdecode(data, flags)`` after the PNG check, with OpenCV's log silenced; None when it cannot decode.

    InputError (``name``: what is wrong) for a damaged PNG.
    """
    data = clean_png(data, name)
    with opencv_log_silenced():
        return cv2.imdecode(np.frombuffer(data, np.uint8), flags)
