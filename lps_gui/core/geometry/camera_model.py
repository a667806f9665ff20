"""The camera model of SPEC section 2 (OpenCV's), with analytic Jacobians.

Projection of camera-frame points ``x_cam`` through the pinhole with
Brown-Conrady distortion ``(k1, k2, p1, p2, k3)`` and, when a lens needs them,
OpenCV's rational ``(k4, k5, k6)`` and thin-prism ``(s1, s2, s3, s4)`` terms
(:data:`HIGHER_NAMES`, held fixed by the session estimators: a real lens always
leaves some misfit to the 5-coefficient model, and an estimate through the
wrong model fakes tilts). Jacobians come back with respect to the camera-frame
point (chain into any pose parametrization), to the 9 intrinsics in
:data:`INTRINSIC_NAMES` order, which is also the order of
cv2.calibrateCameraExtended's standard deviations, and (:func:`higher_rows`)
to the 7 higher terms.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from lps_gui.errors import InputError

INTRINSIC_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")
HIGHER_NAMES = ("k4", "k5", "k6", "s1", "s2", "s3", "s4")  # OpenCV's dist[5:12]: rational, then thin-prism


@dataclass(frozen=True)
class CameraIntrinsics:
    """Intrinsics of one camera; lengths in px, distortion unitless.

    ``covariance`` (9x9, :data:`INTRINSIC_NAMES` order) is what the total
    position uncertainty propagates; when only standard deviations are known
    it is diagonal.
    """

    image_size: tuple[int, int]  # (width, height) px
    camera_matrix: np.ndarray  # shape (3, 3)
    dist: np.ndarray  # shape (5,): k1, k2, p1, p2, k3
    covariance: np.ndarray | None = None  # shape (9, 9)
    rms_px: float | None = None
    n_views: int | None = None
    extra: dict = field(default_factory=dict)
    higher: np.ndarray | None = None  # shape (7,): k4, k5, k6, s1, s2, s3, s4

    def __post_init__(self) -> None:
        K = np.asarray(self.camera_matrix, dtype=float).reshape(3, 3)
        d = np.zeros(5)
        given = np.asarray(self.dist, dtype=float).ravel()
        if given.size > 14 or (given.size > 12 and np.any(given[12:] != 0)):
            raise InputError(
                "intrinsics: the tilted-sensor terms (tauX, tauY) are not supported; "
                "recalibrate with the 5, 8 or 12-coefficient model (lps intrinsics --model rational)"
            )
        d[: min(5, given.size)] = given[:5]
        high = np.zeros(7)
        if self.higher is not None:
            high[:] = np.asarray(self.higher, dtype=float).ravel()
        elif given.size > 5:
            high[: min(7, given.size - 5)] = given[5:12]
        object.__setattr__(self, "camera_matrix", K)
        object.__setattr__(self, "dist", d)
        object.__setattr__(self, "higher", high)
        object.__setattr__(self, "image_size", (int(self.image_size[0]), int(self.image_size[1])))
        if self.covariance is not None:
            object.__setattr__(self, "covariance", np.asarray(self.covariance, dtype=float).reshape(9, 9))

    @property
    def has_higher(self) -> bool:
        """True when the lens has rational or thin-prism terms (the slower projection path)."""
        return bool(np.any(self.higher != 0))

    @property
    def cv_dist(self) -> np.ndarray:
        """The distortion as OpenCV takes it: 5 coefficients, or 12 with the rational and thin-prism terms."""
        return np.concatenate([self.dist, self.higher]) if self.has_higher else self.dist

    @property
    def fx(self) -> float:
        return float(self.camera_matrix[0, 0])

    @property
    def fy(self) -> float:
        return float(self.camera_matrix[1, 1])

    @property
    def cx(self) -> float:
        return float(self.camera_matrix[0, 2])

    @property
    def cy(self) -> float:
        return float(self.camera_matrix[1, 2])

    def vector(self) -> np.ndarray:
        """The 9 intrinsics in :data:`INTRINSIC_NAMES` order."""
        return np.array([self.fx, self.fy, self.cx, self.cy, *self.dist])

    def std(self) -> np.ndarray | None:
        """Standard deviations in :data:`INTRINSIC_NAMES` order, if known."""
        if self.covariance is None:
            return None
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def with_vector(self, v: np.ndarray) -> "CameraIntrinsics":
        """A copy with the 9 intrinsics replaced (covariance kept)."""
        v = np.asarray(v, dtype=float)
        K = np.array([[v[0], 0.0, v[2]], [0.0, v[1], v[3]], [0.0, 0.0, 1.0]])
        return replace(self, camera_matrix=K, dist=v[4:9].copy())

    @classmethod
    def from_values(
        cls,
        image_size: tuple[int, int],
        fx: float,
        fy: float,
        cx: float,
        cy: float,
        dist: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0),
        std: np.ndarray | None = None,
    ) -> "CameraIntrinsics":
        K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        cov = None if std is None else np.diag(np.asarray(std, dtype=float) ** 2)
        return cls(image_size=image_size, camera_matrix=K, dist=np.asarray(dist, float), covariance=cov)


class Projection(NamedTuple):
    """Projected pixels and, when asked for, their Jacobians."""

    uv: np.ndarray  # shape (..., 2) px
    d_uv_d_xcam: np.ndarray | None  # shape (..., 2, 3) px/mm
    d_uv_d_intrinsics: np.ndarray | None  # shape (..., 2, 9)


class ProjectionParts(NamedTuple):
    """Projection as separate contiguous component arrays (the solvers' fast path)."""

    u: np.ndarray
    v: np.ndarray
    du: tuple[np.ndarray, np.ndarray, np.ndarray] | None  # d u / d (x, y, z)
    dv: tuple[np.ndarray, np.ndarray, np.ndarray] | None  # d v / d (x, y, z)
    xp: np.ndarray  # normalized undistorted coordinates, for intrinsics Jacobians
    yp: np.ndarray
    xd: np.ndarray  # normalized distorted coordinates
    yd: np.ndarray


def project_parts(
    x: np.ndarray, y: np.ndarray, z: np.ndarray, intrinsics: CameraIntrinsics, want_jacobian: bool = False
) -> ProjectionParts:
    """Project camera-frame coordinates given as three arrays of any one shape.

    Same model as :func:`project`; avoids packing so that each output is a
    contiguous array (strided writes dominate the cost at K*N ~ 2e5 points).
    """
    if intrinsics.has_higher:
        return _project_parts_higher(x, y, z, intrinsics, want_jacobian)
    fx, fy, cx, cy = intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy
    k1, k2, p1, p2, k3 = intrinsics.dist
    inv_z = 1.0 / z
    xp = x * inv_z
    yp = y * inv_z
    xx, yy, xy = xp * xp, yp * yp, xp * yp
    r2 = xx + yy
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = xp * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xx)
    yd = yp * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * xy
    u = fx * xd + cx
    v = fy * yd + cy
    du = dv = None
    if want_jacobian:
        dr = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)  # d radial / d r2
        cross = 2.0 * xy * dr + 2.0 * p1 * xp + 2.0 * p2 * yp  # d xd / d yp == d yd / d xp
        dxd_dxp = radial + 2.0 * xx * dr + 2.0 * p1 * yp + 6.0 * p2 * xp
        dyd_dyp = radial + 2.0 * yy * dr + 6.0 * p1 * yp + 2.0 * p2 * xp
        du, dv = _to_camera_frame(fx * inv_z, fy * inv_z, xp, yp, (dxd_dxp, cross, cross, dyd_dyp))
    return ProjectionParts(u, v, du, dv, xp, yp, xd, yd)


def _to_camera_frame(fx_z: np.ndarray, fy_z: np.ndarray, xp: np.ndarray, yp: np.ndarray,
                     d: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> tuple[tuple, tuple]:
    """d u, d v / d (x, y, z) from the distortion's d (xd, yd) / d (xp, yp) = ``d`` (xx, xy, yx, yy)."""
    du_dx, du_dy = fx_z * d[0], fx_z * d[1]
    dv_dx, dv_dy = fy_z * d[2], fy_z * d[3]
    return (du_dx, du_dy, -(du_dx * xp + du_dy * yp)), (dv_dx, dv_dy, -(dv_dx * xp + dv_dy * yp))


def _rational(intrinsics: CameraIntrinsics, r2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Numerator, denominator of the rational radial factor and their derivatives in r2."""
    k1, k2, _, _, k3 = intrinsics.dist
    k4, k5, k6 = intrinsics.higher[:3]
    num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6))
    return num, den, k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2), k4 + r2 * (2.0 * k5 + 3.0 * k6 * r2)


def _project_parts_higher(x: np.ndarray, y: np.ndarray, z: np.ndarray, intrinsics: CameraIntrinsics,
                          want_jacobian: bool) -> ProjectionParts:
    """:func:`project_parts` with OpenCV's rational and thin-prism terms (cv2.projectPoints' 12-coefficient model)."""
    fx, fy, cx, cy = intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy
    _, _, p1, p2, _ = intrinsics.dist
    s1, s2, s3, s4 = intrinsics.higher[3:]
    inv_z = 1.0 / z
    xp, yp = x * inv_z, y * inv_z
    xx, yy, xy = xp * xp, yp * yp, xp * yp
    r2 = xx + yy
    num, den, dnum, dden = _rational(intrinsics, r2)
    radial = num / den
    xd = xp * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xx) + r2 * (s1 + s2 * r2)
    yd = yp * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * xy + r2 * (s3 + s4 * r2)
    u, v = fx * xd + cx, fy * yd + cy
    du = dv = None
    if want_jacobian:
        dr = (dnum - radial * dden) / den  # d radial / d r2
        px_, py_ = 2.0 * (s1 + 2.0 * s2 * r2), 2.0 * (s3 + 2.0 * s4 * r2)  # d prism / d r2, times 2 (d r2 = 2 x dx)
        common = 2.0 * xy * dr + 2.0 * p1 * xp + 2.0 * p2 * yp
        dxd_dxp = radial + 2.0 * xx * dr + 2.0 * p1 * yp + 6.0 * p2 * xp + px_ * xp
        dxd_dyp = common + px_ * yp
        dyd_dxp = common + py_ * xp
        dyd_dyp = radial + 2.0 * yy * dr + 6.0 * p1 * yp + 2.0 * p2 * xp + py_ * yp
        du, dv = _to_camera_frame(fx * inv_z, fy * inv_z, xp, yp, (dxd_dxp, dxd_dyp, dyd_dxp, dyd_dyp))
    return ProjectionParts(u, v, du, dv, xp, yp, xd, yd)


def higher_rows(parts: ProjectionParts, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """d u / d (k4, k5, k6, s1, s2, s3, s4) and d v / d them, each shape (7,) + parts' shape.

    What a lens misfit the session's model holds fixed does to the pixels: the
    basis of the lens-model uncertainty of single-plane tilts.
    """
    fx, fy = intrinsics.fx, intrinsics.fy
    xp, yp = parts.xp, parts.yp
    r2 = xp * xp + yp * yp
    num, den, _, _ = _rational(intrinsics, r2)
    g = -num / den**2  # d radial / d k4 per r2
    Ju = np.zeros((7,) + xp.shape)
    Jv = np.zeros((7,) + xp.shape)
    for j, power in enumerate((r2, r2 * r2, r2 * r2 * r2)):
        Ju[j], Jv[j] = fx * xp * g * power, fy * yp * g * power
    Ju[3], Ju[4] = fx * r2, fx * r2 * r2
    Jv[5], Jv[6] = fy * r2, fy * r2 * r2
    return Ju, Jv


def intrinsics_rows(parts: ProjectionParts, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """d u / d intrinsics and d v / d intrinsics, each shape (9,) + parts' shape (parameter-major, contiguous)."""
    fx, fy = intrinsics.fx, intrinsics.fy
    xp, yp, xd, yd = parts.xp, parts.yp, parts.xd, parts.yd
    xx, yy, xy = xp * xp, yp * yp, xp * yp
    r2 = xx + yy
    r4 = r2 * r2
    Ju = np.zeros((9,) + xp.shape)
    Jv = np.zeros((9,) + xp.shape)
    Ju[0], Jv[1] = xd, yd
    Ju[2], Jv[3] = 1.0, 1.0
    fxp, fyp = fx * xp, fy * yp
    if intrinsics.has_higher:  # the radial polynomial is divided by the rational denominator
        den = _rational(intrinsics, r2)[1]
        fxp, fyp = fxp / den, fyp / den
    Ju[4], Jv[4] = fxp * r2, fyp * r2
    Ju[5], Jv[5] = fxp * r4, fyp * r4
    Ju[6], Jv[6] = 2.0 * fx * xy, fy * (r2 + 2.0 * yy)
    Ju[7], Jv[7] = fx * (r2 + 2.0 * xx), 2.0 * fy * xy
    Ju[8], Jv[8] = Ju[5] * r2, Jv[5] * r2
    return Ju, Jv


def intrinsics_jacobian(parts: ProjectionParts, intrinsics: CameraIntrinsics) -> np.ndarray:
    """d uv / d intrinsics, shape (..., 2, 9), from the parts of a projection (the rows of :func:`intrinsics_rows`)."""
    Ju, Jv = intrinsics_rows(parts, intrinsics)
    return np.stack([np.moveaxis(Ju, 0, -1), np.moveaxis(Jv, 0, -1)], axis=-2)


def project(
    x_cam: np.ndarray,
    intrinsics: CameraIntrinsics,
    want_jacobian: bool = False,
    want_intrinsics_jacobian: bool = False,
) -> Projection:
    """Project camera-frame points to pixels (SPEC section 2).

    Parameters
    ----------
    x_cam : shape (..., 3), mm, camera frame (z forward)
    intrinsics : the camera
    want_jacobian : also return d uv / d x_cam, shape (..., 2, 3)
    want_intrinsics_jacobian : also return d uv / d intrinsics, shape (..., 2, 9)
    """
    x_cam = np.asarray(x_cam, dtype=float)
    parts = project_parts(x_cam[..., 0], x_cam[..., 1], x_cam[..., 2], intrinsics, want_jacobian)
    uv = np.stack([parts.u, parts.v], axis=-1)
    d_x = None
    if want_jacobian:
        d_x = np.stack([np.stack(parts.du, axis=-1), np.stack(parts.dv, axis=-1)], axis=-2)
    d_i = intrinsics_jacobian(parts, intrinsics) if want_intrinsics_jacobian else None
    return Projection(uv, d_x, d_i)


def project_board(
    R_cam_board: np.ndarray,
    t_cam_board: np.ndarray,
    points_board: np.ndarray,
    intrinsics: CameraIntrinsics,
) -> np.ndarray:
    """Pixels of board points seen from one or many poses.

    Parameters
    ----------
    R_cam_board : shape (..., 3, 3)
    t_cam_board : shape (..., 3) mm
    points_board : shape (N, 3) mm
    Returns shape (..., N, 2) px.
    """
    x_cam = np.einsum("...ij,nj->...ni", R_cam_board, points_board) + np.asarray(t_cam_board)[..., None, :]
    return project(x_cam, intrinsics).uv


def pose_jacobian_rodrigues(
    rvec: np.ndarray, tvec: np.ndarray, points_board: np.ndarray, intrinsics: CameraIntrinsics
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels and their Jacobians in cv2.projectPoints' parametrization.

    Returns uv shape (N, 2); d uv / d (rvec, tvec, fx, fy, cx, cy, dist) shape
    (N, 2, 15) in cv2's column order, so cv2.projectPoints is a reference for
    tests; and d uv / d board point, shape (N, 2, 3). The Rodrigues
    derivative comes from cv2.Rodrigues (3x9, row-major dR).
    """
    import cv2

    R, dR_drvec = cv2.Rodrigues(np.asarray(rvec, dtype=float).reshape(3, 1))
    dR_drvec = dR_drvec.reshape(3, 3, 3)  # [k, i, j] = d R_ij / d rvec_k
    X = np.asarray(points_board, dtype=float)
    x_cam = X @ R.T + np.asarray(tvec, dtype=float).ravel()
    proj = project(x_cam, intrinsics, want_jacobian=True, want_intrinsics_jacobian=True)
    dx_drvec = np.einsum("kij,nj->nik", dR_drvec, X)  # (N, 3, 3)
    J = np.empty(X.shape[:-1] + (2, 15))
    J[..., 0:3] = np.einsum("nab,nbk->nak", proj.d_uv_d_xcam, dx_drvec)
    J[..., 3:6] = proj.d_uv_d_xcam
    J[..., 6:15] = proj.d_uv_d_intrinsics
    return proj.uv, J, proj.d_uv_d_xcam @ R
