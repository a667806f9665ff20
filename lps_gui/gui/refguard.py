"""Work around PySide6 6.12 on Python 3.11 dropping references to None, True and False.

PySide6 6.12 treats ``None``/``True``/``False`` as immortal (true only from
Python 3.12 on): every void method call (``setText``, ``setValue``...) and
some bool conversions give back a reference they never took. A window that
repaints a readout several times a second would drive ``None``'s count (a
few thousand at start) to zero within a minute and the interpreter aborts
("none_dealloc"). We add a very large number of references once, directly to
the reference counts, so the count can never reach zero in the life of the
process. Those objects are never deallocated anyway. No-op on 3.12+.
"""
from __future__ import annotations

import ctypes
import sys

RESERVE = 1 << 40  # ~1e12 references: ~30 years at 1000 lost references per second

_done = False


def protect_singletons() -> None:
    """Make None, True and False effectively immortal (once per process, CPython < 3.12 only)."""
    global _done
    if _done or sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return
    for obj in (None, True, False):
        ctypes.c_ssize_t.from_address(id(obj)).value += RESERVE  # ob_refcnt is PyObject's first field
    _done = True
