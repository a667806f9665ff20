"""Progress reporting and cancellation shared by every long job.

Long work is a blocking function that takes a ``progress(done, total, message)``
callback and a :class:`CancelToken`; the CLI draws a bar from the callback, the
GUI wraps the same function in a worker thread. No Qt here.
"""
from __future__ import annotations

import threading
from typing import Callable, Protocol

from lps_gui.errors import Cancelled


class ProgressFn(Protocol):
    def __call__(self, done: int, total: int, message: str = "") -> None: ...


def no_progress(done: int, total: int, message: str = "") -> None:
    """The default callback: report nothing."""


class CancelToken:
    """A thread-safe stop request checked by long work between steps."""

    def __init__(self) -> None:
        self._event = threading.Event()

    def cancel(self) -> None:
        self._event.set()

    @property
    def cancelled(self) -> bool:
        return self._event.is_set()

    def check(self, what: str = "work") -> None:
        """Raise :class:`Cancelled` if a stop was requested."""
        if self._event.is_set():
            raise Cancelled(f"{what} cancelled; results so far are kept")


NEVER_CANCELLED = CancelToken()
StopCheck = Callable[[], bool]
