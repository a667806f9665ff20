"""Keep Python's ``None`` alive across PySide6 6.12 calls on Python 3.11.

PySide6 6.12 returns ``None`` from void C++ methods (QPainter.drawLine,
setPen, ...) without taking a reference, as if ``None`` were immortal (it is
only from Python 3.12 on). On 3.11 every such call drops one reference to
``None``; a long report (tens of thousands of paint calls) brings the count
to zero and the interpreter aborts ("none_dealloc"). :class:`NoneRefGuard`
measures the loss and pays it back with permanent references (Py_IncRef,
never released, not even at interpreter shutdown, when PySide6's own
objects release theirs), so the count never falls below where it started.
Harmless where the bug is absent. No Qt here.
"""
from __future__ import annotations

import ctypes
import sys
from types import TracebackType

PREFUND = 100_000  # covers the calls between two top-ups with a wide margin


def _incref_none(n: int) -> None:
    """Add ``n`` references to None that are never released."""
    incref = ctypes.pythonapi.Py_IncRef
    incref.argtypes = [ctypes.py_object]
    incref.restype = None
    obj = ctypes.py_object(None)
    for _ in range(n):
        incref(obj)


class NoneRefGuard:
    """Context manager: prefund ``None`` references, top up on demand, pay back the loss at exit."""

    def __init__(self, prefund: int = PREFUND):
        self.prefund = prefund
        self.base = 0

    def __enter__(self) -> "NoneRefGuard":
        if sys.version_info < (3, 12):
            _incref_none(self.prefund)
        self.base = sys.getrefcount(None)
        return self

    def topup(self) -> None:
        """Restore the count of ``None`` references to at least its level at entry."""
        if sys.version_info >= (3, 12):
            return
        deficit = self.base - sys.getrefcount(None)
        if deficit > 0:
            _incref_none(deficit)

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.topup()
