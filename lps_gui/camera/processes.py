"""How the image layers start worker processes (detection, rendering)."""
from __future__ import annotations

import multiprocessing
import multiprocessing.context
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from typing import Callable


def process_context() -> multiprocessing.context.BaseContext:
    """Worker processes are spawned, never forked.

    A forked child inherits OpenCV's thread pool in whatever state the
    parent's threads left it (and a GUI's threads' locks): the child then
    hangs in its first cv2.setNumThreads or parallel call. Spawned workers
    start clean; the price is a slower start-up, and a calling script needs
    the usual ``if __name__ == "__main__":`` guard.
    """
    return multiprocessing.get_context("spawn")


def end_with_parent(parent_pid: int) -> None:
    """In a worker: have the kernel kill it when its parent dies (Linux ``PR_SET_PDEATHSIG``).

    A ``lps detect --workers N`` ended by SIGTERM, SIGHUP or SIGKILL runs no Python cleanup: without this its
    workers (and, through them, multiprocessing's resource tracker) ran on detached. A parent already gone
    before the request took effect ends the worker at once.
    """
    if not sys.platform.startswith("linux"):
        return
    import ctypes
    import signal

    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):  # no prctl in this libc: the parent's own cleanup is all there is
        return
    if os.getppid() != parent_pid:
        os._exit(1)


PR_SET_PDEATHSIG = 1


def _start_worker(parent_pid: int, initializer: Callable[[], None] | None) -> None:
    end_with_parent(parent_pid)
    if initializer is not None:
        initializer()


def worker_pool(max_workers: int, initializer: Callable[[], None] | None = None) -> ProcessPoolExecutor:
    """A spawned process pool whose workers end with this process, however it ends."""
    return ProcessPoolExecutor(max_workers=max_workers, mp_context=process_context(), initializer=_start_worker,
                               initargs=(os.getpid(), initializer))
