"""Central finite differences, and the comparison the Jacobian tests use.

The tolerance must let a wrong term fail: a Jacobian column scaled by 1.01
moves its entries by 1e-2 relative, and central differences here are good to
~1e-8, so the checks compare every entry at 1e-5 of its own scale.
"""
from __future__ import annotations

from typing import Callable

import numpy as np


def central_jacobian(f: Callable[[np.ndarray], np.ndarray], n: int, h: float | np.ndarray) -> np.ndarray:
    """d f / d x at x = 0 for a perturbation function ``f(dx)``; shape f(0).shape + (n,)."""
    h = np.broadcast_to(np.asarray(h, dtype=float), (n,))
    cols = []
    for j in range(n):
        e = np.zeros(n)
        e[j] = h[j]
        cols.append((np.asarray(f(e)) - np.asarray(f(-e))) / (2.0 * h[j]))
    return np.stack(cols, axis=-1)


def normalized_difference(analytic: np.ndarray, numeric: np.ndarray) -> float:
    """Largest |analytic - numeric| of a symmetric normal matrix in units of sqrt(N_ii N_jj)."""
    d = np.sqrt(np.abs(np.diag(numeric)))
    return float(np.max(np.abs(analytic - numeric) / np.maximum(np.outer(d, d), 1e-300)))


def column_difference(analytic: np.ndarray, numeric: np.ndarray) -> float:
    """Largest |analytic - numeric| of each column (last axis) relative to that column's largest entry."""
    a = analytic.reshape(-1, analytic.shape[-1])
    n = numeric.reshape(-1, numeric.shape[-1])
    scale = np.maximum(np.max(np.abs(n), axis=0), 1e-300)
    return float(np.max(np.max(np.abs(a - n), axis=0) / scale))
