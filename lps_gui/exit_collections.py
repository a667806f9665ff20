"""Skip the interpreter's garbage collections at exit: the ``lps`` command calls this when its work is done.

At exit CPython runs full garbage collections over every object still alive
(modules, functions, classes: some 40k after ``lps estimate``), measured
35 ms of the 50 ms from the last line printed to the process' end. Objects
moved to the permanent generation by :func:`gc.freeze` are skipped; they are
still freed by reference counting as the modules are torn down, and atexit
handlers (log files) run as before. Only reference cycles left at exit are
not collected, as the operating system reclaims the memory anyway.

A process-wide setting, so only an entry point calls it. ``main`` may run
many times in one process (the tests): :func:`collect_again` at its start
gives what an earlier call froze back to the collector.
"""
from __future__ import annotations

import gc


def freeze_for_exit() -> None:
    """Move every object alive now out of reach of the collector (the exit's collections then skip them)."""
    gc.freeze()


def collect_again() -> None:
    """Undo :func:`freeze_for_exit`: frozen objects are collected as usual again."""
    gc.unfreeze()
