"""One OpenBLAS thread per process for the apps: the block threads use the cores instead.

Our matrix products are small (a block's 300 x 540 corners against 540 x 13
board moments, 6x6 and 17x17 systems). OpenBLAS still hands them to its
worker threads, which spin-wait between calls; numpy and scipy each bring a
pool. On a loaded machine those spinning pools take the cores from the
block threads: a pose pass runs several times slower with them.
The variable only takes effect before numpy is first imported, so the entry
points (``lps``, ``lps-gui``, the test session) call this first; a value the
user set is kept.
"""
from __future__ import annotations

import os

BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS",)


def limit_blas_threads() -> None:
    """Default every BLAS pool of this process (and its children) to one thread."""
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
