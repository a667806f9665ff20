"""The lens-model error of a calibration, measured from its own views (issue 35).

A lens the 5-coefficient model cannot follow (rational, thin-prism terms) leaves residuals that look like noise
on the calibration set, yet biases its parameters by many of their stated sigmas (docs/validation.md, hon-lens2):
the covariance the fit reports is the corners' noise only. What the misfit does show is that the parameters depend
on which views they are fitted to: each view sees the image and the depths differently, so a model that is wrong
moves with the view set, and a session at other depths and angles sees yet another compromise. Delete-one-view
refits (the jackknife) measure that spread. Where the model is exact the spread is the noise the covariance already
holds (whitened eigenvalues about 1; with ~10 views their chance spread reaches ~4-6); a direction whose spread
stands far above it (eigenvalue > :data:`EIG_SIGNIFICANT`) is model error, and its excess over the noise is the
model-error covariance the estimate then propagates with the rest.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.intrinsics.refine import refine_intrinsics

EIG_SIGNIFICANT = 9.0  # a direction whose view-to-view spread is 3x the noise's (in sigma) is the model's, not chance
MIN_JACKKNIFE_VIEWS = 5  # fewer views: the spread is no measure of anything


@dataclass(frozen=True)
class ModelError:
    """The model-error covariance (9x9, INTRINSIC_NAMES order) and the whitened jackknife eigenvalues it came from."""

    covariance: np.ndarray
    eigenvalues: np.ndarray  # descending, in units of the noise covariance

    @property
    def significant(self) -> bool:
        return bool(np.any(self.covariance != 0.0))

    def to_dict(self) -> dict:
        """intrinsics.json ``model_error``: what was added to ``covariance`` and why."""
        return {"covariance": self.covariance.tolist(), "jackknife_eigenvalues": np.round(self.eigenvalues, 3).tolist(),
                "significant_above": EIG_SIGNIFICANT}


def excess_covariance(jackknife: np.ndarray, covariances: np.ndarray, noise: np.ndarray,
                      threshold: float = EIG_SIGNIFICANT) -> ModelError:
    """Model-error covariance from delete-one estimates ``jackknife`` (n, 9), their covariances (n, 9, 9) and the
    full fit's noise covariance (9, 9).

    The jackknife covariance D = (n-1)/n sum (v_j - mean)(v_j - mean)^T is compared with what the noise alone
    would give it, E = (n-1)/n sum (C_j - C) (dropping a view adds its information's worth of noise: a view with
    much leverage moves the fit much, and that is no misfit). D is whitened by E; each eigen-direction above
    ``threshold`` contributes its excess (eigenvalue - 1) of E. Held (zero-variance) parameters stay out.
    """
    v = np.asarray(jackknife, float)
    n = len(v)
    free = np.diag(noise) > 0
    out = np.zeros_like(noise)
    if n < MIN_JACKKNIFE_VIEWS or not free.any():
        return ModelError(out, np.zeros(0))
    d = (v - v.mean(axis=0))[:, free]
    D = (n - 1) / n * d.T @ d
    sub = np.ix_(free, free)
    E = (n - 1) / n * np.sum([np.asarray(c, float)[sub] - noise[sub] for c in covariances], axis=0)
    E = (E + E.T) / 2 + 1e-9 * np.diag(np.diag(noise[sub]))  # never singular where a view adds nothing
    lam_e, U = np.linalg.eigh(E)
    if lam_e[0] <= 0:  # not a noise covariance: rebuild it from its positive part
        lam_e = np.maximum(lam_e, 1e-12 * lam_e[-1])
    L = U * np.sqrt(lam_e)  # E = L L^T
    W = np.linalg.solve(L, np.linalg.solve(L, D).T)  # L^-1 D L^-T
    lam, V = np.linalg.eigh((W + W.T) / 2)
    excess = np.where(lam > threshold, lam - 1.0, 0.0)
    out[sub] = L @ (V * excess) @ V.T @ L.T
    return ModelError((out + out.T) / 2, lam[::-1])


def jackknife_intrinsics(size_mm: tuple[float, float], X_views: list[np.ndarray], uv_views: list[np.ndarray],
                         corner_ids: list[np.ndarray], view_ids: list[int], intrinsics, rvecs: list[np.ndarray],
                         tvecs: list[np.ndarray], free: np.ndarray, estimate_warp: bool) -> tuple[np.ndarray, np.ndarray]:
    """The 9 intrinsics refitted without each view in turn, (n, 9), and their covariances (n, 9, 9); started
    from the full fit (a few LM steps), on the corners it kept."""
    out, covs = [], []
    for j in range(len(X_views)):
        keep = [i for i in range(len(X_views)) if i != j]
        ref = refine_intrinsics(size_mm, [X_views[i] for i in keep], [uv_views[i] for i in keep],
                                [corner_ids[i] for i in keep], [view_ids[i] for i in keep], intrinsics,
                                [rvecs[i] for i in keep], [tvecs[i] for i in keep], free, estimate_warp=estimate_warp,
                                reject_outliers=False)  # the full fit's outliers are gone already
        out.append(np.asarray(ref.intrinsics_vector, float)[:9])
        covs.append(np.asarray(ref.covariance, float)[:9, :9])
    return np.array(out), np.array(covs)
