"""What the estimator takes and gives for D = 1 or 2 axes: options and the one estimate type with its covariance."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.estimator.methods import METHODS, METHODS_BY_AXES
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.models.constant_orientation import BoardPlaneMotion
from lps_gui.core.models.hybrid import HybridOptions
from lps_gui.core.models.joint_lm import LpsState
from lps_gui.core.models.planar_model import PlanarState, affine_coefficients
from lps_gui.core.models.six_dof import SixDof
from lps_gui.core.numerics.arrowhead import ArrowheadInverse
from lps_gui.errors import InputError

PRIOR_JITTER = 1e-18  # keeps an intrinsics covariance with exact zeros invertible


@dataclass(frozen=True)
class Selections:
    """Which parameter groups a solve moves, as mrcal's problem selections (the others are held).

    The shared stage parameters (rotation, line or plane) and every view's
    position on its D axes are always free. The board's warp is held as the
    intrinsics calibration found it; the target poses of SPEC 13 (rows,
    constellations) are one more group, free whenever the observations name
    targets (:mod:`lps_gui.core.estimator.target_estimate`).
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
    # intrinsics free with their covariance as prior (SPEC 4.6); None: the session decides (a row of targets does,
    # pipeline.estimate.resolve_self_calibration)
    self_calibrate: bool | None = None
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
class PlanarFit:
    """Affine fit measured = offset + G target (+ backlash offsets) of a plane's positions, stage frame."""

    G: np.ndarray  # shape (2, 2): columns are the measured +X and +Y motion per commanded mm
    cov_G: np.ndarray  # shape (4, 4): covariance of G.ravel() (row-major), from noise and the intrinsics
    residual_um: np.ndarray  # shape (K, 2): measured - fit (NaN for unused views)


@dataclass
class LpsEstimate:
    """Everything the estimator found for a stage of D = 1 or 2 axes; ``pipeline.estimate`` turns it into
    results.json.

    Positions and their sigmas are shaped as the observations' targets: (K,) on a line, (K, 2) on a plane
    (:attr:`positions_mm`, :attr:`D`). The fields after ``intrinsics_gradient`` belong to one D and are None
    (empty) for the other.
    """

    method: str
    options: EstimateOptions
    state: LpsState | PlanarState  # positions relative to the reference view (a plane's in the stage frame)
    reference_view: int
    usable: np.ndarray  # shape (K,) bool: board seen
    used: np.ndarray  # shape (K,) bool: in the final solve
    outlier: np.ndarray  # shape (K,) bool
    outlier_reason: list[str]
    sigma_px: float  # a-posteriori noise of one corner coordinate
    sigma_s_mm: np.ndarray  # shape (K,) or (K, 2): from noise
    sigma_total_mm: np.ndarray  # shape (K,) or (K, 2): noise + intrinsics
    rms_px: np.ndarray  # shape (K,) per-view RMS reprojection error under the model
    n_corners: np.ndarray  # shape (K,)
    iterations: int
    converged: bool
    n_observations: int
    dof: int
    flags: list[dict[str, Any]]
    timings_s: dict[str, float]
    inverse: ArrowheadInverse | None = None  # of the final solve, in units of sigma_px^2 (b = D unknowns a view)
    intrinsics_gradient: np.ndarray | None = None  # shape (K, 9) or (K, 2, 9): d positions / d intrinsics
    # D = 1
    step_sigma_mm: np.ndarray | None = None  # shape (K,): sigma of s_i - s_prev (same run, direction); NaN for the first
    parameter_sigmas: dict[str, Any] = field(default_factory=dict)
    six_dof: SixDof | None = None
    board_plane: BoardPlaneMotion | None = None  # straightness at the board plane, image rotation (SPEC 11)
    position_model: str = "line"  # "board plane": the positions of the per-view fit (core.estimator.board_plane_positions)
    line_model_sigma_px: float | None = None  # the line model's a-posteriori sigma when the per-view fit replaced it
    # D = 2
    cov_mm2: np.ndarray | None = None  # shape (K, 2, 2): each view's position covariance, from noise
    cov_total_mm2: np.ndarray | None = None  # shape (K, 2, 2): with the intrinsics' covariance
    fit: PlanarFit | None = None  # the affine motion of the grid

    @property
    def positions_mm(self) -> np.ndarray:
        """s (K,) on a line, (x, y) (K, 2) on a plane, zero at the reference view."""
        return self.state.positions

    @property
    def D(self) -> int:
        return 1 if self.positions_mm.ndim == 1 else self.positions_mm.shape[1]

    def functional_covariance(self, L: np.ndarray, with_intrinsics: bool = False) -> np.ndarray:
        """Covariance (mm^2) of m linear functionals of the positions, L shape (m, K) or (m, K, D) -> (m, m).

        Uses the full covariance, so correlations between positions (a common
        distance or direction error is a scale error of every position) count;
        ``with_intrinsics`` adds the intrinsics' covariance propagated.
        """
        L = np.asarray(L, dtype=float)
        L = np.where(self.used[None, :, None], L.reshape(L.shape[0], self.used.size, -1), 0.0)
        if self.inverse is None:
            cov = self.cov_mm2 if self.cov_mm2 is not None else (self.sigma_s_mm**2)[:, None, None]
            return np.einsum("mka,kab,nkb->mn", L, cov, L)
        out = self.sigma_px**2 * self.inverse.functional_covariance(L)
        cov_I = self.state.intrinsics.covariance
        if with_intrinsics and self.intrinsics_gradient is not None and cov_I is not None:
            GL = np.einsum("mka,kai->mi", L, self.intrinsics_gradient.reshape(L.shape[1], L.shape[2], -1))
            out = out + GL @ cov_I @ GL.T
        return out

    def linear_functional_sigma(self, a: np.ndarray) -> tuple[float, float]:
        """Sigma (mm) of sum_i a_i . s_i (a shaped as the positions) from noise alone and in total (with intrinsics)."""
        a = np.asarray(a, dtype=float)[None]
        return (float(np.sqrt(self.functional_covariance(a)[0, 0])),
                float(np.sqrt(self.functional_covariance(a, with_intrinsics=True)[0, 0])))

    def deviation_um(self, target_mm: np.ndarray) -> np.ndarray:
        """measured - (target - target of the reference), um, shaped as the positions; zero at the reference."""
        t = np.asarray(target_mm, dtype=float)
        return 1e3 * (self.positions_mm - (t - t[self.reference_view]))


def sigmas_of(cov: np.ndarray) -> np.ndarray:
    """Per-view 1-sigma of each coordinate (K, b) from their covariance blocks (K, b, b)."""
    return np.sqrt(np.maximum(np.einsum("kii->ki", cov), 0.0))


def planar_fit(est: LpsEstimate, target_mm: np.ndarray, approach: np.ndarray) -> PlanarFit:
    """Affine fit of a plane's measured positions with the covariance of G from the full position covariance.

    The intrinsics' covariance is in it (a line's scale sigma is the total one too): fx, fy and the principal point
    scale and shear the whole grid alike, so unlike the noise they do not average out over the stops (issue 35: on
    the campaign's planar cell they raise scale Y's sigma by 9-15 %)."""
    used = est.used
    Phi, coef = affine_coefficients(est.state.xy, target_mm, approach, used)
    G = coef[1:3].T  # shape (2, 2): G[:, 0] is +X motion, G[:, 1] is +Y motion
    pinv = np.zeros((Phi.shape[1], Phi.shape[0]))
    pinv[:, used] = np.linalg.pinv(Phi[used])
    # coef[j, a] = sum_k pinv[j, k] xy[k, a]; G[a, b] = coef[1 + b, a]
    L = np.zeros((4, est.state.xy.shape[0], 2))
    for a in range(2):
        for b in range(2):
            L[2 * a + b, :, a] = pinv[1 + b]
    cov_G = est.functional_covariance(L, with_intrinsics=True)
    resid = 1e3 * (est.state.xy - Phi @ coef)
    resid[~used] = np.nan
    return PlanarFit(G, cov_G, resid)


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
