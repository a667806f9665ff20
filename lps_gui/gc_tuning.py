"""When the garbage collector runs: none over work that makes no cycles, none over everything at exit.

CPython's cyclic collector runs full collections over every object alive
(modules, functions, the estimator's state: 40-100k objects) when enough new
containers survive. Two moments where that is pure cost:

- Building and writing results: trees of dicts and lists of floats, freed by
  reference counting, with no cycles to find; yet K = 1600 position rows
  trigger a full collection. :func:`paused` holds the collector off
  for such a block and restores it after.
- Exit: the interpreter collects everything alive again (most of the time
  from ``lps estimate``'s last line to the process' end). Objects moved to the
  permanent generation by :func:`gc.freeze` are skipped; reference counting
  still frees them as the modules are torn down and atexit handlers (log
  files) run as before. Only cycles left at exit are not collected, and the
  operating system reclaims that memory anyway. :func:`freeze_for_exit` is
  process-wide, so only an entry point calls it (``lps``'s ``main``), which may
  run many times in one process (the tests): :func:`collect_again` at its start
  gives an earlier call's frozen objects back to the collector.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def paused() -> Iterator[None]:
    """No cyclic collection inside the block (for work that creates no reference cycles); the previous state after."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def freeze_for_exit() -> None:
    """Move every object alive now out of reach of the collector (the exit's collections then skip them)."""
    gc.freeze()


def collect_again() -> None:
    """Undo :func:`freeze_for_exit`: frozen objects are collected as usual again."""
    gc.unfreeze()
