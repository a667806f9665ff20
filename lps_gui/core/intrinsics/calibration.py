"""Intrinsics from varied-pose board views (SPEC 6), with what tells whether to trust them.

cv2.calibrateCameraExtended gives the 9 intrinsics and each one's standard
deviation (in :data:`INTRINSIC_NAMES` order, which is also our covariance
order), and a per-view RMS. On top: how well the corners cover the image (a
coarse grid of counts), views whose removal lowers the error markedly, and
warnings when coverage is poor or the views are too alike (then the focal
length trades off against the distance and is undetermined, the paper's
reason to calibrate intrinsics apart from the LPS run).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import cv2
import numpy as np

from lps_gui.core.geometry.camera_model import HIGHER_NAMES, INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.intrinsics.model_error import excess_covariance, jackknife_intrinsics
from lps_gui.core.intrinsics.refine import RejectedCorner, WarpNotSeparableError, refine_intrinsics
from lps_gui.errors import DegenerateGeometryError, InputError

if TYPE_CHECKING:
    from lps_gui.core.intrinsics.residual_structure import ResidualStructure

WARP_MODES = ("auto", "on", "off")

MIN_VIEWS = 3
MIN_CORNERS_PER_VIEW = 6
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


@dataclass
class IntrinsicsCalibration:
    """Result of :func:`calibrate_intrinsics`; views are indexed as given."""

    intrinsics: CameraIntrinsics  # full 9x9 covariance (INTRINSIC_NAMES order), diag = std^2
    std: np.ndarray  # shape (9,), INTRINSIC_NAMES order
    rms_px: float  # RMS length of the 2-D reprojection error over the kept corners (OpenCV's figure; sqrt(2) x per-axis sigma)
    per_view_rms_px: np.ndarray  # shape (V,), same measure per view over all its corners (rejected ones too), NaN for views not used
    coverage: np.ndarray  # shape (grid_rows, grid_cols): corners per image cell
    flagged_views: list[int]
    warnings: list[str]
    used_views: list[int]
    rvecs: np.ndarray  # shape (V, 3), NaN for views not used
    tvecs: np.ndarray  # shape (V, 3) mm
    view_names: list[str] = field(default_factory=list)
    warp_mm: np.ndarray | None = None  # (bow_x, bow_y) of the board, None when not estimated
    warp_sigma_mm: np.ndarray | None = None
    rejected_corners: list[RejectedCorner] = field(default_factory=list)
    residuals_px: list[np.ndarray] = field(default_factory=list)  # per view (N, 2) observed - projected, NaN where not seen
    image_points: list[np.ndarray] = field(default_factory=list)  # per view (N, 2) px as given
    row_of: np.ndarray | None = None  # (N,) the board row of each corner (neighbours for the noise estimate)

    def coverage_on(self, grid: tuple[int, int]) -> np.ndarray:
        """Corner counts of the used views on another (cols, rows) grid."""
        pts = [self.image_points[k] for k in self.used_views]
        return coverage_grid(np.concatenate(pts), self.intrinsics.image_size, grid)

    def residual_structure(self) -> "ResidualStructure | None":
        """The used views' residuals binned over the image: does the lens model fit (issue 35)?"""
        from lps_gui.core.intrinsics.residual_structure import residual_structure

        if not self.residuals_px or not self.image_points:
            return None
        res = {k: self.residuals_px[k].copy() for k in self.used_views}
        for c in self.rejected_corners:  # outliers are not the lens's
            res[c.view][c.corner] = np.nan
        uv = np.stack([self.image_points[k] for k in self.used_views])
        return residual_structure(uv, np.stack([res[k] for k in self.used_views]), self.intrinsics.image_size,
                                  self.row_of)

    def coverage_fraction(self) -> float:
        return float(np.mean(self.coverage > 0))

    def summary(self) -> str:
        """Human-readable lines: each parameter with its std, error figures, flags, warnings."""
        lines = [f"{name:>3} = {v:12.6g} +- {s:.3g}" for name, v, s in zip(INTRINSIC_NAMES, self.intrinsics.vector(), self.std)]
        if self.intrinsics.has_higher:
            lines += [f"{name:>3} = {v:12.6g} (held at OpenCV's value)"
                      for name, v in zip(HIGHER_NAMES, self.intrinsics.higher)]
        lines.append(f"rms = {self.rms_px:.4f} px over {len(self.used_views)} views; coverage {100 * self.coverage_fraction():.0f} % of the image grid")
        if self.warp_mm is not None:
            lines.append(
                f"board bow = {self.warp_mm[0]:+.3f} +- {self.warp_sigma_mm[0]:.3f} mm along x, "
                f"{self.warp_mm[1]:+.3f} +- {self.warp_sigma_mm[1]:.3f} mm along y (centre relative to the edges)"
            )
        if self.rejected_corners:
            lines.append(f"rejected {len(self.rejected_corners)} corner(s) as outliers:")
            for c in self.rejected_corners:
                name = self.view_names[c.view] if c.view < len(self.view_names) else f"view {c.view}"
                lines.append(f"  {name} corner {c.corner}: residual {c.residual_px:.2f} px")
        for i in self.flagged_views:
            name = self.view_names[i] if i < len(self.view_names) else f"view {i}"
            lines.append(f"flagged: {name} (rms {self.per_view_rms_px[i]:.3f} px): removing it lowers the error markedly")
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _calibrate(objs: list[np.ndarray], imgs: list[np.ndarray], image_size: tuple[int, int], flags: int):
    try:
        return cv2.calibrateCameraExtended(objs, imgs, tuple(image_size), None, None, flags=flags, criteria=CRITERIA)
    except cv2.error as exc:
        raise DegenerateGeometryError(
            f"intrinsics: OpenCV calibration failed ({str(exc).strip().splitlines()[-1]}); add views at varied tilts"
        ) from exc


def coverage_grid(points_px: np.ndarray, image_size: tuple[int, int], grid: tuple[int, int] = (8, 6)) -> np.ndarray:
    """Corner counts per cell of a (cols x rows) grid over the image, shape (rows, cols)."""
    w, h = image_size
    pts = points_px[np.all(np.isfinite(points_px), axis=-1)]
    counts, _, _ = np.histogram2d(pts[:, 1], pts[:, 0], bins=(grid[1], grid[0]), range=((0, h), (0, w)))
    return counts.astype(int)


def _tilt_spread_deg(rvecs: np.ndarray) -> float:
    """Largest angle between the board normals of any two views, degrees."""
    normals = np.array([cv2.Rodrigues(r.reshape(3, 1))[0][:, 2] for r in rvecs])
    cosines = np.clip(normals @ normals.T, -1.0, 1.0)
    return float(np.degrees(np.arccos(cosines.min())))


def calibrate_intrinsics(
    object_points: np.ndarray,
    image_points: list[np.ndarray],
    image_size: tuple[int, int],
    flags: int = 0,
    grid: tuple[int, int] = (8, 6),
    flag_k: float = 5.0,
    warp: str = "auto",
    reject_outliers: bool = True,
    model_error: bool = False,
) -> IntrinsicsCalibration:
    """Calibrate a camera from board views.

    Parameters
    ----------
    object_points : shape (N, 3) mm, board corners (SPEC 2 order)
    image_points : V arrays of shape (N, 2) px, NaN where a corner is missing
    image_size : (width, height) px
    flags : cv2.CALIB_* flags (e.g. cv2.CALIB_FIX_K3)
    grid : coverage grid (cols, rows)
    flag_k : a view is a candidate outlier when its RMS exceeds the median
        by ``flag_k`` robust sigmas; it is flagged when dropping it lowers
        the overall RMS by more than 10 %.
    warp : "auto" estimates the board's bow with the intrinsics and falls
        back to a flat board (with a warning) when the views cannot separate
        it; "on" raises :class:`WarpNotSeparableError` then; "off" = flat.
    reject_outliers : drop single corners far beyond the noise (listed in
        ``rejected_corners``).
    model_error : refit without each view in turn and add the lens-model error that spread shows beyond the noise
        to the covariance (:mod:`lps_gui.core.intrinsics.model_error`; recorded in ``extra["model_error"]``).

    OpenCV's calibration (flat board) is the starting point; the joint
    refinement of :func:`refine_intrinsics` gives the final values, the
    covariance and the residuals.
    """
    if warp not in WARP_MODES:
        raise InputError(f"intrinsics: warp must be one of {', '.join(WARP_MODES)}, got {warp!r}")
    X = np.asarray(object_points, dtype=np.float32).reshape(-1, 3)
    objs, imgs, used, ids, warnings = [], [], [], [], []
    for k, uv in enumerate(image_points):
        uv = np.asarray(uv, dtype=float).reshape(-1, 2)
        if uv.shape[0] != X.shape[0]:
            raise InputError(f"intrinsics: view {k} has {uv.shape[0]} corners but the board has {X.shape[0]}")
        ok = np.all(np.isfinite(uv), axis=-1)
        if ok.sum() < MIN_CORNERS_PER_VIEW:
            continue
        objs.append(X[ok])
        imgs.append(uv[ok].astype(np.float32).reshape(-1, 1, 2))
        used.append(k)
        ids.append(np.flatnonzero(ok))
    V = len(image_points)
    if len(used) < MIN_VIEWS:
        raise DegenerateGeometryError(
            f"intrinsics: {len(used)} usable views (of {V}); need at least {MIN_VIEWS}, better 15-30 at varied tilts"
        )
    rms, K, dist, rvecs, tvecs, std_int, _, per_view = _calibrate(objs, imgs, image_size, flags)
    std = np.asarray(std_int, dtype=float).ravel()[:9]
    per_view_rms = np.full(V, np.nan)
    per_view_rms[used] = np.asarray(per_view).ravel()
    r_all = np.full((V, 3), np.nan)
    t_all = np.full((V, 3), np.nan)
    r_all[used] = np.array([r.ravel() for r in rvecs])
    t_all[used] = np.array([t.ravel() for t in tvecs])

    flagged = _flag_views(objs, imgs, used, per_view_rms, image_size, flags, float(rms), flag_k)
    coverage = coverage_grid(np.concatenate([i.reshape(-1, 2) for i in imgs]), image_size, grid)
    warnings += _warnings(coverage, r_all[used], std, K, len(used))
    seed = CameraIntrinsics(image_size, K, np.asarray(dist, dtype=float).ravel()[:12])  # 5, or 12 with higher terms
    X64 = X.astype(float)
    size_mm = (float(np.ptp(X64[:, 0])), float(np.ptp(X64[:, 1])))
    args = (size_mm, [X64[i] for i in ids], [np.asarray(image_points[k], float).reshape(-1, 2)[i] for k, i in zip(used, ids)],
            ids, used, seed, [np.ravel(r) for r in rvecs], [np.ravel(t) for t in tvecs], std > 0)
    try:
        ref = refine_intrinsics(*args, estimate_warp=warp != "off", reject_outliers=reject_outliers)
    except WarpNotSeparableError as exc:
        if warp == "on":
            raise
        warnings.append(f"board bow not estimated: {str(exc).split('; ')[0].removeprefix('intrinsics: ')}")
        ref = refine_intrinsics(*args, estimate_warp=False, reject_outliers=reject_outliers)
    intr = seed.with_vector(ref.intrinsics_vector)
    covariance, extra = ref.covariance, {}
    if model_error:
        live = [k for k, kk in enumerate(ref.kept) if kk.sum() >= MIN_CORNERS_PER_VIEW]  # the fit's corners only
        jk, jk_cov = jackknife_intrinsics(size_mm, [args[1][k][ref.kept[k]] for k in live],
                                          [args[2][k][ref.kept[k]] for k in live], [ids[k][ref.kept[k]] for k in live],
                                          [used[k] for k in live], replace(intr, covariance=ref.covariance),
                                          [ref.rvecs[k] for k in live], [ref.tvecs[k] for k in live], args[8],
                                          ref.warp_mm is not None)
        found = excess_covariance(jk, jk_cov, ref.covariance)
        covariance, extra = ref.covariance + found.covariance, {"model_error": found.to_dict()}
        if found.significant:
            warnings.append("the intrinsics move with the view set far beyond the corner noise (a lens the model "
                            "does not follow): that spread is added to their covariance; a richer lens model "
                            "(--model auto) or more varied views would narrow it")
    std = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    residuals = [np.full((X.shape[0], 2), np.nan) for _ in range(V)]
    for k, i, r in zip(used, ids, ref.residuals_px):
        residuals[k][i] = r
    per_view_rms = np.full(V, np.nan)
    per_view_rms[used] = [np.sqrt(np.nanmean(np.sum(residuals[k] ** 2, axis=1))) for k in used]
    r2 = np.concatenate([np.sum(r[kk] ** 2, axis=1) for r, kk in zip(ref.residuals_px, ref.kept)])
    rms = float(np.sqrt(np.mean(r2)))
    r_all[used] = np.array(ref.rvecs)
    t_all[used] = np.array(ref.tvecs)
    intr = CameraIntrinsics(
        image_size=image_size,
        camera_matrix=intr.camera_matrix,
        dist=intr.dist,
        higher=intr.higher,
        covariance=covariance,
        rms_px=rms,
        n_views=len(used),
        extra=extra,
    )
    warp_sigma = None if ref.warp_cov is None else np.sqrt(np.diag(ref.warp_cov))
    cal = IntrinsicsCalibration(intr, std, rms, per_view_rms, coverage, flagged, warnings, used, r_all, t_all,
                                 warp_mm=ref.warp_mm, warp_sigma_mm=warp_sigma, rejected_corners=ref.rejected,
                                 residuals_px=residuals, row_of=np.unique(X64[:, 1], return_inverse=True)[1],
                                 image_points=[np.asarray(u, float).reshape(-1, 2) for u in image_points])
    structure = cal.residual_structure()
    if structure is not None:  # what a session's lens-model check and tilt uncertainty read (intrinsics.json lens_fit)
        cal.intrinsics = replace(cal.intrinsics, extra={**cal.intrinsics.extra, "lens_fit": structure.to_dict()})
        if structure.exceeds_noise:
            cal.warnings.append(structure.message("these views"))
    return cal


def _flag_views(objs, imgs, used, per_view_rms, image_size, flags, rms, flag_k) -> list[int]:
    """Views far above the typical per-view error whose removal lowers the total RMS > 10 %."""
    vals = per_view_rms[used]
    med = float(np.median(vals))
    mad = 1.4826 * float(np.median(np.abs(vals - med)))
    limit = med + flag_k * max(mad, 0.1 * med)
    flagged = []
    if len(used) <= MIN_VIEWS:
        return flagged
    for j, k in enumerate(used):
        if per_view_rms[k] <= limit:
            continue
        rest = [i for i in range(len(used)) if i != j]
        rms_without = _calibrate([objs[i] for i in rest], [imgs[i] for i in rest], image_size, flags)[0]
        if rms_without < 0.9 * rms:
            flagged.append(k)
    return flagged


def _warnings(coverage: np.ndarray, rvecs: np.ndarray, std: np.ndarray, K: np.ndarray, n_used: int) -> list[str]:
    out = []
    frac = float(np.mean(coverage > 0))
    border = np.concatenate([coverage[0], coverage[-1], coverage[1:-1, 0], coverage[1:-1, -1]])
    if frac < 0.75 or np.mean(border > 0) < 0.5:
        out.append(
            f"corners cover {100 * frac:.0f} % of the image grid ({100 * np.mean(border > 0):.0f} % of its border cells); "
            "add views with the board near the edges and corners, or distortion is extrapolated"
        )
    spread = _tilt_spread_deg(rvecs)
    if spread < 20.0:
        out.append(
            f"the views are too similar (board normals within {spread:.0f} deg); the focal length is poorly "
            "determined: tilt the board 20-45 deg in different directions"
        )
    if std[0] > 0.01 * K[0, 0] or std[1] > 0.01 * K[1, 1]:
        out.append(f"focal length uncertain: fx +- {std[0]:.1f} px ({100 * std[0] / K[0, 0]:.1f} %); add more varied views")
    if n_used < 10:
        out.append(f"only {n_used} views; 15-30 give reliable distortion coefficients")
    return out
