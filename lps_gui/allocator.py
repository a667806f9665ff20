"""Keep freed numpy temporaries in the heap instead of returning them to the OS.

The solvers create many (K, N) temporaries of a few MB. glibc serves blocks
above its mmap threshold with fresh mmap'd pages and unmaps them on free, so
every temporary page-faults its memory back in: measured 5x slower on the
joint LM's linearization at K=400, N=540. Raising the mmap and trim
thresholds (what MALLOC_MMAP_THRESHOLD_ does from the environment) keeps
them in the heap. No effect off glibc.

A process-wide setting, so the entry points call it (``lps``, ``lps-gui``,
the test session, the benchmarks), never the math in ``core``.
"""
from __future__ import annotations

import ctypes
import sys

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_done = False


def _libc() -> ctypes.CDLL:
    """glibc by its usual name; find_library (which runs ldconfig at every start) only when that fails."""
    try:
        return ctypes.CDLL("libc.so.6")
    except OSError:
        from ctypes.util import find_library

        return ctypes.CDLL(find_library("c") or "libc.so.6")


def tune_allocator(mmap_threshold_bytes: int = 64 << 20, trim_threshold_bytes: int = 512 << 20) -> bool:
    """Raise glibc's mmap/trim thresholds once per process; True if applied."""
    global _done
    if _done or not sys.platform.startswith("linux"):
        return _done
    try:
        libc = _libc()
        ok = libc.mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold_bytes)) == 1
        ok &= libc.mallopt(_M_TRIM_THRESHOLD, int(trim_threshold_bytes)) == 1
    except (OSError, AttributeError):
        return False
    _done = bool(ok)
    return _done
