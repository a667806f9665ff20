"""How the image layers start worker processes (detection, rendering)."""
from __future__ import annotations

import multiprocessing
import multiprocessing.context


def process_context() -> multiprocessing.context.BaseContext:
    """Worker processes are spawned, never forked.

    A forked child inherits OpenCV's thread pool in whatever state the
    parent's threads left it (and a GUI's threads' locks): the child then
    hangs in its first cv2.setNumThreads or parallel call. Spawned workers
    start clean; the price is a slower start-up, and a calling script needs
    the usual ``if __name__ == "__main__":`` guard.
    """
    return multiprocessing.get_context("spawn")
