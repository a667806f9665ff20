"""Projection uncertainty of a calibration, and the cross-validation of two (mrcal's projection diff).

A calibration's covariance says how far its projection of a fixed ray may be
off: J_intrinsics Sigma J_intrinsics^T, a 2x2 covariance per pixel (the poses
are already marginalized in Sigma). Its worst direction, sqrt of the largest
eigenvalue, is the uncertainty map. The covariance is of the intrinsics
alone, so the map is the same at every distance.

Two calibrations of the same camera from disjoint halves of the views must
agree within their combined uncertainty. As mrcal-show-projection-diff does,
a grid of pixels is unprojected by the first model, the rotation that best
maps its rays onto the second model's rays is fitted (the camera frame of a
calibration is only defined up to such a rotation), and the rotated rays are
projected by the second model. The difference, measured in units of the
combined sigma, says whether the model and the data hold up: a lens the
model cannot follow, a board that changed shape, or a focus change between
the halves all show as a difference beyond the noise.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project

if TYPE_CHECKING:
    from lps_gui.core.intrinsics.calibration import IntrinsicsCalibration

# the normalized RMS difference (~1 for a perfect model and Gaussian noise) above which the halves disagree; the
# grid cells are strongly correlated (one focal-length error moves them all), so the figure behaves like one |z|:
# 3 keeps false alarms near 0.3 %
CONSISTENCY_LIMIT = 3.0


def pixel_grid(image_size: tuple[int, int], grid: tuple[int, int] = (16, 12)) -> np.ndarray:
    """Cell centres of a (cols x rows) grid over the image, shape (rows, cols, 2) px."""
    w, h = image_size
    u = (np.arange(grid[0]) + 0.5) * w / grid[0]
    v = (np.arange(grid[1]) + 0.5) * h / grid[1]
    uu, vv = np.meshgrid(u, v)
    return np.stack([uu, vv], axis=-1)


def unproject(uv: np.ndarray, intr: CameraIntrinsics) -> np.ndarray:
    """Unit rays (..., 3) in the camera frame of pixels (..., 2); NaN where the model does not reach the pixel.

    cv2.undistortPoints starts, Newton steps on :func:`project` finish (to
    ~1e-9 px); a pixel the distortion polynomial folds over (beyond where
    the corners were) does not converge and gets NaN.
    """
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-14)
    q = np.asarray(uv, dtype=float).reshape(-1, 2)
    xy = cv2.undistortPoints(q.reshape(-1, 1, 2), intr.camera_matrix, intr.cv_dist, criteria=crit).reshape(-1, 2)
    x = np.column_stack([xy, np.ones(len(xy))])
    for _ in range(5):
        proj = project(x, intr, want_jacobian=True)
        J = proj.d_uv_d_xcam[:, :, :2]
        ok = np.abs(np.linalg.det(J)) > 1e-12
        x[ok, :2] -= np.linalg.solve(J[ok], (proj.uv - q)[ok][..., None])[..., 0]
    bad = ~(np.linalg.norm(project(x, intr).uv - q, axis=1) < 1e-6)
    x[bad] = np.nan
    v = x / np.linalg.norm(x, axis=1, keepdims=True)
    return v.reshape(np.shape(uv)[:-1] + (3,))


def _intrinsics_jacobian(rays: np.ndarray, intr: CameraIntrinsics) -> np.ndarray:
    """d uv / d intrinsics at rays (G, 3), stacked (2G, 9)."""
    return project(rays, intr, want_intrinsics_jacobian=True).d_uv_d_intrinsics.reshape(-1, 9)


def _rotation_jacobian(rays: np.ndarray, intr: CameraIntrinsics, h: float = 1e-6) -> np.ndarray:
    """d uv / d small rotation (axis-angle) of the rays, stacked (2G, 3), by central differences."""
    from lps_gui.core.geometry.rotation import exp_so3

    cols = []
    for k in range(3):
        w = np.zeros(3)
        w[k] = h
        cols.append((project(rays @ exp_so3(w).T, intr).uv - project(rays @ exp_so3(-w).T, intr).uv).ravel() / (2 * h))
    return np.column_stack(cols)


def _rotation_free_blocks(jacobians: list[np.ndarray], covariances: list[np.ndarray], J_rot: np.ndarray,
                          weights: np.ndarray) -> np.ndarray:
    """Per-point 2x2 covariances (G, 2, 2) of projections once the best rotation is taken out.

    A rotation moves every projection by J_rot omega; fitting omega by
    weighted least squares removes that part of any intrinsics error, so
    what is left is M J dtheta with M = I - J_rot (J_rot^T W J_rot)^-1 J_rot^T W.
    """
    W = np.repeat(weights, 2)
    P = np.linalg.solve((J_rot * W[:, None]).T @ J_rot, (J_rot * W[:, None]).T)  # (3, 2G)
    out = 0.0
    for J, cov in zip(jacobians, covariances):
        MJ = (J - J_rot @ (P @ J)).reshape(-1, 2, 9)
        out = out + np.einsum("gai,ij,gbj->gab", MJ, cov, MJ)
    return out


def _weights(jacobians: list[np.ndarray], covariances: list[np.ndarray]) -> np.ndarray:
    """1 / variance of each grid point's raw projection: extrapolated corners count little in the rotation fit."""
    var = sum(np.einsum("gai,ij,gaj->g", J.reshape(-1, 2, 9), c, J.reshape(-1, 2, 9)) for J, c in zip(jacobians, covariances))
    return 1.0 / np.maximum(var, 1e-30)


def _require_covariance(intr: CameraIntrinsics) -> np.ndarray:
    if intr.covariance is None:
        raise ValueError("projection uncertainty needs the intrinsics' covariance")
    return intr.covariance


def worst_sigma(cov2: np.ndarray) -> np.ndarray:
    """sqrt of the largest eigenvalue of each 2x2 covariance (...) px."""
    return np.sqrt(np.clip(np.linalg.eigvalsh(cov2)[..., -1], 0.0, None))


def uncertainty_map(intr: CameraIntrinsics, grid: tuple[int, int] = (16, 12)) -> tuple[np.ndarray, np.ndarray]:
    """(pixels (rows, cols, 2), worst-direction projection sigma (rows, cols) px) over the image.

    The sigma is of the projection once the best-fitting rotation of the
    camera frame is taken out (a principal-point error near the centre is
    indistinguishable from a rotation), as mrcal reports it.
    """
    q = pixel_grid(intr.image_size, grid)
    rays = unproject(q.reshape(-1, 2), intr)
    ok = np.all(np.isfinite(rays), axis=1)
    J, cov = _intrinsics_jacobian(rays[ok], intr), _require_covariance(intr)
    blocks = _rotation_free_blocks([J], [cov], _rotation_jacobian(rays[ok], intr), _weights([J], [cov]))
    sigma = np.full(len(rays), np.nan)
    sigma[ok] = worst_sigma(blocks)
    return q, sigma.reshape(q.shape[:2])


def fit_rotation(a: np.ndarray, b: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """R minimizing sum w |R a - b|^2 over unit rays (N, 3) (weighted Kabsch)."""
    H = (a * weights[:, None]).T @ b
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    return Vt.T @ np.diag([1.0, 1.0, d]) @ U.T


@dataclass
class ProjectionDiff:
    """Difference of two calibrations' projections over an image grid, after the best common rotation."""

    pixels: np.ndarray  # shape (rows, cols, 2) px
    diff_px: np.ndarray  # shape (rows, cols, 2): model b minus model a
    sigma_px: np.ndarray  # shape (rows, cols): worst-direction combined sigma
    normalized: np.ndarray  # shape (rows, cols): sqrt(d^T Sigma^-1 d / 2), ~1 where the models agree
    rotation: np.ndarray  # shape (3, 3): rays of a -> rays of b
    judged: np.ndarray  # shape (rows, cols) bool: cells where both calibrations saw corners

    @property
    def figure(self) -> float:
        """RMS of the normalized difference over the judged cells: ~1 for consistent models."""
        return float(np.sqrt(np.mean(self.normalized[self.judged] ** 2)))

    @property
    def consistent(self) -> bool:
        return self.figure <= CONSISTENCY_LIMIT

    def verdict(self) -> str:
        mag = np.linalg.norm(self.diff_px, axis=-1)[self.judged]
        if mag.size == 0:
            return "not judged: no grid cell is seen by both calibrations"
        sig = self.sigma_px[self.judged]
        words = "consistent" if self.consistent else "the model or the data falls short"
        return (
            f"{words}: the two halves differ by {self.figure:.2f} x their combined sigma "
            f"(RMS over the {mag.size} grid cells both saw; limit {CONSISTENCY_LIMIT:g}); median difference "
            f"{np.median(mag):.3f} px against median sigma {np.median(sig):.3f} px, worst {mag.max():.3f} px"
        )


def projection_diff(
    a: CameraIntrinsics, b: CameraIntrinsics, grid: tuple[int, int] = (16, 12), judged: np.ndarray | None = None
) -> ProjectionDiff:
    """Compare two calibrations of one camera (mrcal-show-projection-diff with the fitted rotation).

    The rotation is fitted in pixels (Kabsch on the rays, then Gauss-Newton)
    with each grid point weighted by its inverse raw variance, and the
    predicted covariance of the difference has the same rotation taken out.
    ``judged`` (rows, cols) bool picks the cells the verdict is made on
    (default all): where neither calibration saw corners both extrapolate.
    """
    from lps_gui.core.geometry.rotation import exp_so3

    if tuple(a.image_size) != tuple(b.image_size):
        raise ValueError(f"cannot compare calibrations of different image sizes {a.image_size} and {b.image_size}")
    shape = (grid[1], grid[0])
    q_all = pixel_grid(a.image_size, grid).reshape(-1, 2)
    ra_all, rb_all = unproject(q_all, a), unproject(q_all, b)
    ok = np.all(np.isfinite(ra_all), axis=1) & np.all(np.isfinite(rb_all), axis=1)
    q, ra, rb = q_all[ok], ra_all[ok], rb_all[ok]
    Ja, Jb = _intrinsics_jacobian(ra, a), _intrinsics_jacobian(rb, b)
    covs = [_require_covariance(a), _require_covariance(b)]
    weights = _weights([Ja, Jb], covs)
    R = fit_rotation(ra, rb, weights)
    W = np.repeat(weights, 2)
    for _ in range(3):
        rot = ra @ R.T
        d = (project(rot, b).uv - q).ravel()
        Jr = _rotation_jacobian(rot, b)
        step = np.linalg.solve((Jr * W[:, None]).T @ Jr, (Jr * W[:, None]).T @ d)
        R = exp_so3(-step) @ R
    rot = ra @ R.T
    d = project(rot, b).uv - q
    Jb = _intrinsics_jacobian(rot, b)
    cov = _rotation_free_blocks([Ja, Jb], covs, _rotation_jacobian(rot, b), weights)
    m2 = np.einsum("na,nab,nb->n", d, np.linalg.pinv(cov), d)
    diff, sigma, norm = np.full((ok.size, 2), np.nan), np.full(ok.size, np.nan), np.full(ok.size, np.nan)
    diff[ok], sigma[ok], norm[ok] = d, worst_sigma(cov), np.sqrt(m2 / 2.0)
    judge = ok if judged is None else ok & np.asarray(judged, dtype=bool).ravel()
    return ProjectionDiff(
        pixels=q_all.reshape(shape + (2,)),
        diff_px=diff.reshape(shape + (2,)),
        sigma_px=sigma.reshape(shape),
        normalized=norm.reshape(shape),
        rotation=R,
        judged=judge.reshape(shape),
    )


@dataclass
class CrossValidation:
    """Two calibrations from the even and the odd views and their projection difference."""

    even: "IntrinsicsCalibration"
    odd: "IntrinsicsCalibration"
    diff: ProjectionDiff
    even_views: list[int]
    odd_views: list[int]

    def summary(self) -> str:
        lines = [f"cross-validation: {len(self.even_views)} even views against {len(self.odd_views)} odd views"]
        for name, cal in (("even", self.even), ("odd", self.odd)):
            s = cal.std
            v = cal.intrinsics.vector()
            lines.append(f"  {name:>4}: fx {v[0]:.2f} +- {s[0]:.2f}, fy {v[1]:.2f} +- {s[1]:.2f}, "
                         f"cx {v[2]:.2f} +- {s[2]:.2f}, cy {v[3]:.2f} +- {s[3]:.2f} px")
        lines.append(self.diff.verdict())
        return "\n".join(lines)


def cross_validate(
    object_points: np.ndarray,
    image_points: list[np.ndarray],
    image_size: tuple[int, int],
    grid: tuple[int, int] = (16, 12),
    **calibrate_kwargs,
) -> CrossValidation:
    """Calibrate the even and the odd views apart and compare the two projections.

    ``calibrate_kwargs`` go to :func:`calibrate_intrinsics` (flags, warp, ...).
    """
    from lps_gui.core.intrinsics.calibration import calibrate_intrinsics

    even = list(range(0, len(image_points), 2))
    odd = list(range(1, len(image_points), 2))
    cal_even = calibrate_intrinsics(object_points, [image_points[k] for k in even], image_size, **calibrate_kwargs)
    cal_odd = calibrate_intrinsics(object_points, [image_points[k] for k in odd], image_size, **calibrate_kwargs)
    seen = (cal_even.coverage_on(grid) > 0) & (cal_odd.coverage_on(grid) > 0)
    diff = projection_diff(cal_even.intrinsics, cal_odd.intrinsics, grid, judged=seen if seen.any() else None)
    return CrossValidation(cal_even, cal_odd, diff, even, odd)


# ----------------------------------------------------------------------------- choosing the lens model
# mrcal's argument: a lens model is right when it predicts data it was not fitted to. Each candidate is
# calibrated on the even views and on the odd views; every view of the other half is then fitted with its own
# pose only (the intrinsics held), and the held-out residual RMS says how well the model predicts a new view.
# The richer model (OpenCV's rational and thin-prism terms) is chosen only when it predicts clearly better.

LENS_MODELS = {"opencv5": 0, "rational": cv2.CALIB_RATIONAL_MODEL | cv2.CALIB_THIN_PRISM_MODEL}
MIN_IMPROVEMENT = 0.05  # the richer model must lower the held-out RMS by this fraction


def heldout_rms_px(intr: CameraIntrinsics, object_points: np.ndarray, image_points: list[np.ndarray]) -> float:
    """RMS reprojection error (2-D) of views fitted by their pose alone under fixed intrinsics."""
    X = np.asarray(object_points, float).reshape(-1, 3)
    r2 = []
    for uv in image_points:
        uv = np.asarray(uv, float).reshape(-1, 2)
        ok = np.all(np.isfinite(uv), axis=1)
        if ok.sum() < 6:
            continue
        obj, img = X[ok] * np.array([1.0, 1.0, 0.0]), uv[ok]
        good, rvec, tvec = cv2.solvePnP(obj, img, intr.camera_matrix, intr.cv_dist, flags=cv2.SOLVEPNP_IPPE)
        if not good:
            continue
        rvec, tvec = cv2.solvePnPRefineLM(obj, img, intr.camera_matrix, intr.cv_dist, rvec, tvec)
        proj = cv2.projectPoints(obj, rvec, tvec, intr.camera_matrix, intr.cv_dist)[0].reshape(-1, 2)
        r2.append(np.sum((proj - img) ** 2, axis=1))
    return float(np.sqrt(np.mean(np.concatenate(r2)))) if r2 else float("nan")


@dataclass
class LensModelChoice:
    """The lens model cross-validation chose, with each candidate's held-out RMS."""

    model: str
    heldout_rms_px: dict[str, float]

    @property
    def flags(self) -> int:
        return LENS_MODELS[self.model]

    def summary(self) -> str:
        rms = ", ".join(f"{m} {v:.4f} px" for m, v in self.heldout_rms_px.items())
        return (f"lens model: {self.model} (held-out RMS of views fitted by their pose alone: {rms}; the richer model "
                f"is chosen when it lowers it by {100 * MIN_IMPROVEMENT:.0f} %)")


def choose_lens_model(object_points: np.ndarray, image_points: list[np.ndarray], image_size: tuple[int, int],
                      flags: int = 0, **calibrate_kwargs) -> LensModelChoice:
    """The 5-coefficient or the rational/thin-prism model, by two-fold cross-validation of the views."""
    from lps_gui.core.intrinsics.calibration import calibrate_intrinsics

    halves = [list(range(0, len(image_points), 2)), list(range(1, len(image_points), 2))]
    rms = {}
    for model, extra in LENS_MODELS.items():
        r2 = []
        for fit, test in (halves, halves[::-1]):
            cal = calibrate_intrinsics(object_points, [image_points[k] for k in fit], image_size, flags=flags | extra,
                                       **calibrate_kwargs)
            r2.append(heldout_rms_px(cal.intrinsics, object_points, [image_points[k] for k in test]) ** 2)
        rms[model] = float(np.sqrt(np.mean(r2)))
    richer = rms["rational"] < (1.0 - MIN_IMPROVEMENT) * rms["opencv5"]
    return LensModelChoice("rational" if richer else "opencv5", rms)
