"""Independent blocks of views run on the machine's cores.

numpy releases the GIL inside every array operation, and a block of views
is ~17k corners, so two threads over the blocks keep two cores busy with
little lock traffic; processes would have to copy the corners. The pool is
made once, on first use, and lives as long as the process.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Iterable, TypeVar

T = TypeVar("T")
R = TypeVar("R")

MAX_THREADS = 2  # more threads than this gain nothing on memory-bound numpy passes
_PREFIX = "lps-blocks"
_pool: ThreadPoolExecutor | None = None


def worker_count() -> int:
    """Threads for the block passes: the cores this process may use, at most MAX_THREADS; LPS_THREADS overrides."""
    given = os.environ.get("LPS_THREADS", "").strip()
    if given.isdigit() and int(given) > 0:
        return int(given)
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(1, min(MAX_THREADS, cores))


def in_parallel(fn: Callable[[T], R], items: Iterable[T]) -> list[R]:
    """``[fn(x) for x in items]``, on the block threads when there are several items and cores."""
    items = list(items)
    nested = threading.current_thread().name.startswith(_PREFIX)  # a block that runs blocks: no waiting on itself
    if len(items) < 2 or nested or worker_count() < 2:
        return [fn(x) for x in items]
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(worker_count(), thread_name_prefix=_PREFIX)
    return list(_pool.map(fn, items))
