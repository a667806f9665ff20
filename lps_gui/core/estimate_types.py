"""What the estimator takes and gives: options and the estimate with its covariance."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.constant_orientation import BoardPlaneMotion
from lps_gui.core.hybrid import HybridOptions
from lps_gui.core.joint_lm import LpsState
from lps_gui.core.six_dof import SixDof
from lps_gui.core.uncertainty import ArrowheadInverse
from lps_gui.errors import InputError

METHODS = ("joint", "hybrid", "pnp", "calibrate")
METHODS_BY_AXES = {1: METHODS, 2: ("joint", "pnp")}  # the hybrid grid search and Eq. 2 are 1-D by construction
PRIOR_JITTER = 1e-18  # keeps an intrinsics covariance with exact zeros invertible


@dataclass(frozen=True)
class Selections:
    """Which parameter groups a solve moves, as mrcal's problem selections (the others are held).

    The shared stage parameters (rotation, line or plane) and every view's
    position on its D axes are always free. The board's warp is held as the
    intrinsics calibration found it; the target poses of SPEC 13 (rows,
    constellations) are one more group, free whenever the observations name
    targets (:mod:`lps_gui.core.target_estimate`).
    """

    intrinsics: bool = False  # the 9 intrinsics, with the calibration's covariance as prior (SPEC 4.6)
    target_poses: bool = False  # the mounting poses of every target but the first (SPEC 13)


@dataclass
class EstimateOptions:
    """What to estimate and how; every field lands in results.json."""

    method: str = "joint"
    robust: bool = False  # Huber loss in the joint LM
    outlier_k: float = 5.0  # robust sigmas for an outlier view
    detect_outliers: bool = True
    max_outlier_rounds: int = 4
    self_calibrate: bool = False  # intrinsics free with their covariance as prior (SPEC 4.6)
    six_dof: bool = True
    hybrid: HybridOptions = field(default_factory=HybridOptions)

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise InputError(f"method {self.method!r} is unknown; choose one of {', '.join(METHODS)}")
        if not (0 < self.outlier_k < float("inf")):  # NaN too: it would turn outlier detection off
            raise InputError("outlier_k must be positive (robust sigmas, default 5)")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def selections(self) -> Selections:
        """The parameter groups this estimation frees."""
        return Selections(intrinsics=self.self_calibrate)

    def intrinsics_prior(self, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray] | None:
        """(I0, Sigma_I) of the intrinsics when they are selected (free with their calibration as prior), else None."""
        if not self.selections().intrinsics:
            return None
        if intrinsics.covariance is None:
            raise InputError("self-calibration needs the intrinsics' std or covariance in intrinsics.json")
        return intrinsics.vector(), intrinsics.covariance + PRIOR_JITTER * np.eye(len(INTRINSIC_NAMES))

    def check_axes(self, D: int) -> None:
        """InputError when the method or a selection does not exist for a stage of D axes."""
        if self.method not in METHODS_BY_AXES[D]:
            raise InputError(f"method {self.method!r} is not available for a stage of {D} axes; use one of "
                             f"{', '.join(METHODS_BY_AXES[D])} (the hybrid grid search and the full calibration "
                             "are 1-D only)")


@dataclass
class LpsEstimate:
    """Everything the estimator found; ``pipeline.estimate`` turns it into results.json."""

    method: str
    options: EstimateOptions
    state: LpsState  # positions s relative to the reference view
    reference_view: int
    usable: np.ndarray  # shape (K,) bool: board seen
    used: np.ndarray  # shape (K,) bool: in the final solve
    outlier: np.ndarray  # shape (K,) bool
    outlier_reason: list[str]
    sigma_px: float  # a-posteriori noise of one corner coordinate
    sigma_s_mm: np.ndarray  # shape (K,) from noise
    sigma_total_mm: np.ndarray  # shape (K,) noise + intrinsics
    step_sigma_mm: np.ndarray  # shape (K,): sigma of s_i - s_prev (same run, direction); NaN for the first
    rms_px: np.ndarray  # shape (K,) per-view RMS reprojection error under the model
    n_corners: np.ndarray  # shape (K,)
    parameter_sigmas: dict[str, Any]
    iterations: int
    converged: bool
    n_observations: int
    dof: int
    six_dof: SixDof | None
    flags: list[dict[str, Any]]
    timings_s: dict[str, float]
    inverse: ArrowheadInverse | None = None  # of the final solve, in units of sigma_px^2
    intrinsics_gradient: np.ndarray | None = None  # shape (K, 9): d s / d intrinsics
    board_plane: BoardPlaneMotion | None = None  # straightness at the board plane, image rotation (SPEC 11)

    def linear_functional_sigma(self, a: np.ndarray) -> tuple[float, float]:
        """Sigma (mm) of sum_i a_i s_i from noise alone and in total (with intrinsics).

        Uses the full covariance, so correlations between positions (a common
        distance or direction error is a scale error of every position) count.
        """
        a = np.where(self.used, np.asarray(a, dtype=float), 0.0)
        if self.inverse is None:
            var = float(np.sum((a * self.sigma_s_mm) ** 2))
            return np.sqrt(var), np.sqrt(var)
        wa = self.inverse.W.T @ a
        var = self.sigma_px**2 * float(np.sum(a * a * self.inverse.D_inv) + wa @ self.inverse.S_inv @ wa)
        total = var
        if self.intrinsics_gradient is not None and self.state.intrinsics.covariance is not None:
            ga = self.intrinsics_gradient.T @ a
            total += float(ga @ self.state.intrinsics.covariance @ ga)
        return float(np.sqrt(var)), float(np.sqrt(total))

    def deviation_um(self, target_mm: np.ndarray) -> np.ndarray:
        """measured - (target - target of the reference), um; zero at the reference."""
        t = np.asarray(target_mm, dtype=float)
        return 1e3 * (self.state.s - (t - t[self.reference_view]))



def step_pairs(run: np.ndarray, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(previous, current) capture pairs inside each run and direction, in capture order."""
    prev, cur = [], []
    last: dict[tuple[int, float], int] = {}
    for i in range(len(run)):
        key = (int(run[i]), float(direction[i]))
        if key in last:
            prev.append(last[key])
            cur.append(i)
        last[key] = i
    return np.array(prev, dtype=int), np.array(cur, dtype=int)
