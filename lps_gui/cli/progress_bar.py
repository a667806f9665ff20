"""A text progress bar with rate and ETA on stderr (no dependency)."""
from __future__ import annotations

import sys
import time
from typing import TextIO


class ProgressBar:
    """Callable as ``progress(done, total, message)``; redraws at most 10 times a second."""

    def __init__(self, label: str, stream: TextIO | None = None, width: int = 28):
        self.label = label
        self.stream = stream or sys.stderr
        self.width = width
        self.t0 = time.monotonic()
        self._last_draw = 0.0
        self._interactive = self.stream.isatty()
        self._last_percent = -1

    def __call__(self, done: int, total: int, message: str = "") -> None:
        now = time.monotonic()
        final = total > 0 and done >= total
        if not final and now - self._last_draw < 0.1:
            return
        self._last_draw = now
        frac = 0.0 if total <= 0 else min(1.0, done / total)
        elapsed = now - self.t0
        eta = (elapsed / frac - elapsed) if frac > 0 else float("nan")
        filled = int(round(frac * self.width))
        bar = "#" * filled + "-" * (self.width - filled)
        eta_text = "" if final or eta != eta else f" ETA {eta:5.1f}s"
        line = f"{self.label:<12} [{bar}] {done}/{total}{eta_text} {message}"
        if self._interactive:
            self.stream.write("\r" + line[:120].ljust(120))
            if final:
                self.stream.write("\n")
        else:  # logs and pipes: a line per 10 %, no carriage returns
            percent = int(frac * 10)
            if percent != self._last_percent or final:
                self._last_percent = percent
                self.stream.write(line + "\n")
        self.stream.flush()
