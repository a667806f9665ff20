"""The noise and the intrinsics' share of the covariance (SPEC 4, "Uncertainty").

Cov = sigma^2 H^-1 with H^-1 factored on the block arrowhead
(:mod:`lps_gui.core.numerics.arrowhead`) and sigma^2 the a-posteriori noise; the total
position uncertainty adds the intrinsics' covariance propagated through
d s / d I = -H^-1 J^T J_I (:func:`lps_gui.core.numerics.arrowhead.intrinsics_sensitivity`).
"""
from __future__ import annotations

import numpy as np

from lps_gui.errors import DegenerateGeometryError


def noise_variance(ssr: float, n_obs: int, n_params: int) -> float:
    """A-posteriori residual variance sigma_hat^2 = SSR / (2NK - p) (px^2)."""
    dof = n_obs - n_params
    if dof <= 0:
        raise DegenerateGeometryError(
            f"{n_obs} residuals for {n_params} unknowns: no redundancy to estimate the noise; add views or corners"
        )
    return ssr / dof


def propagated_variance(G_s: np.ndarray, cov_intrinsics: np.ndarray) -> np.ndarray:
    """Variance of each position from the intrinsics alone, shape (K,) mm^2."""
    return np.einsum("ki,ij,kj->k", G_s, cov_intrinsics, G_s)
