"""Render a chessboard as a real camera would see it, with exact-area anti-aliasing.

A point-sampled render puts the grey-level step of every edge at the pixel
centre it happens to fall in, which biases detected corners by ~0.3 px. Here
every pixel integrates the board over its footprint: the pixel's ray is
intersected with the board plane, the local Jacobian pixel -> board gives the
footprint's extent along the board axes, and the checker pattern (a product
of two square waves) is box-filtered analytically. The box filter of a square
wave is a difference of triangle waves divided by the width, so the average
is exact for an axis-aligned footprint and unbiased (point-symmetric) for a
skewed one: corners stay where they belong.

What does not change between frames (each pixel's undistorted ray and the
Jacobian of the undistortion) is computed once per camera and process
(:func:`camera_rays`), so a frame is a few vectorized passes over float32 arrays.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project


@dataclass(frozen=True)
class Lighting:
    """Grey levels and optics of a render (8-bit units)."""

    black: float = 35.0  # printed black squares
    white: float = 215.0  # paper
    background: float = 90.0  # whatever is behind the board
    vignetting: float = 0.0  # relative fall-off at the image corners (0 = none)
    blur_px: float = 1.2  # Gaussian optics + defocus sigma (0 = none); real lenses are never sharper than ~1 px
    blur_edge_px: float = 0.0  # > blur_px: the blur grows (as r^2) to this sigma at the image corners (realism)
    texture: float = 0.0  # relative amplitude of the paper texture (0 = none)
    shot_gain: float = 0.0  # shot-noise variance per grey level (0 = none)
    antialias: bool = True  # False: point-sample each pixel centre (for comparison only: biased)


def _undistorted_rays(intrinsics: CameraIntrinsics, lens: Any = None) -> tuple[np.ndarray, ...]:
    """Normalized coordinates (x', y') of every pixel centre and d(x', y') / d(u, v).

    cv2.undistortPoints gives a start; three Newton steps with the analytic
    Jacobian of :func:`project` make the rays exact to ~1e-9 px even where
    the distortion is strong. ``lens`` (a :class:`lps_gui.core.truth.realism.LensMisfit`):
    the true lens has terms beyond the 5-coefficient model; cv2's 12-coefficient
    undistortion starts, four Newton steps on ``lens.distort`` (Jacobian by
    central differences, 1e-7 in x') make the rays exact to ~1e-6 px.
    """
    w, h = intrinsics.image_size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    uv = np.stack([u.ravel(), v.ravel()], axis=-1)  # shape (H*W, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-12)
    dist = intrinsics.cv_dist if lens is None else lens.opencv_dist(intrinsics)
    xy = cv2.undistortPoints(uv.reshape(-1, 1, 2), intrinsics.camera_matrix, dist, criteria=crit).reshape(-1, 2)
    step = _brown_step if lens is None else _lens_step(lens)
    for _ in range(3 if lens is None else 4):
        at, J = step(xy, intrinsics)
        xy = xy - np.linalg.solve(J, (at - uv)[..., None])[..., 0]
    Jinv = np.linalg.inv(step(xy, intrinsics)[1])  # shape (P, 2, 2): d (x', y') / d uv
    f32 = lambda a: np.ascontiguousarray(a.reshape(h, w), dtype=np.float32)  # noqa: E731
    return f32(xy[:, 0]), f32(xy[:, 1]), f32(Jinv[:, 0, 0]), f32(Jinv[:, 0, 1]), f32(Jinv[:, 1, 0]), f32(Jinv[:, 1, 1])


RAYS_CAMERAS = 2  # cameras whose rays a process keeps (a 5 Mpx camera's are 120 MB)
_RAYS: dict[tuple[Any, ...], tuple[np.ndarray, ...]] = {}
_RAYS_LOCK = threading.Lock()


def camera_rays(intrinsics: CameraIntrinsics, lens: Any = None) -> tuple[np.ndarray, ...]:
    """:func:`_undistorted_rays`, kept per camera (read-only): each simulated camera opened, each image set
    and each scene of one camera would otherwise rebuild them (about a second for 640 x 480)."""
    key = (intrinsics.image_size, intrinsics.camera_matrix.tobytes(), intrinsics.dist.tobytes(),
           intrinsics.higher.tobytes(), lens)
    with _RAYS_LOCK:
        rays = _RAYS.get(key)
    if rays is None:
        rays = _undistorted_rays(intrinsics, lens)
        for a in rays:
            a.setflags(write=False)
        with _RAYS_LOCK:
            while len(_RAYS) >= RAYS_CAMERAS:
                _RAYS.pop(next(iter(_RAYS)))
            _RAYS[key] = rays
    return rays


def _brown_step(xy: np.ndarray, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of normalized points (P, 2) and d uv / d (x', y') (P, 2, 2) through the intrinsics' own model (all its coefficients)."""
    proj = project(np.c_[xy, np.ones(len(xy))], intrinsics, want_jacobian=True)
    return proj.uv, proj.d_uv_d_xcam[:, :, :2]


def _lens_step(lens: Any) -> Any:
    """:func:`_brown_step` through a lens with terms beyond the model (Jacobian by central differences)."""
    eps = 1e-7

    def step(xy: np.ndarray, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
        cols = [(lens.distort(xy + d, intrinsics) - lens.distort(xy - d, intrinsics)) / (2 * eps)
                for d in (np.array([eps, 0.0]), np.array([0.0, eps]))]
        return lens.distort(xy, intrinsics), np.stack(cols, axis=-1)
    return step


def _mod2(x: np.ndarray) -> np.ndarray:
    """``np.mod(x, 2.0)`` in [0, 2) without its division: x - 2 floor(x / 2) rounds nothing for normal x (it
    is a multiple of x's last bit below 2), so the same numbers, ~40 times faster (the render's dearest step)."""
    return x - 2.0 * np.floor(x * 0.5)


def _triangle(x: np.ndarray) -> np.ndarray:
    """Integral of the unit square wave (+1 on [0,1), -1 on [1,2)), period 2."""
    return 1.0 - np.abs(_mod2(x) - 1.0)


def _box_square_wave(x: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Mean of the square wave over [x - width/2, x + width/2] (exact)."""
    half = 0.5 * width
    return (_triangle(x + half) - _triangle(x - half)) / width


WIDE_BLUR_SQUARES = 0.1  # below this blur (squares) a kink 0.5 square away adds < 1e-20: only the nearest counts


KINK_TABLE_STEP = 1.0 / 256.0  # the kink's profile tabulated over a = |t|/s in [0, 8] (f(8) ~ 1e-16), linear between
_KINK_TABLE: np.ndarray | None = None


def _kink_table() -> np.ndarray:
    """f(a) = phi(a) - a Phi(-a) on the table's grid, float32 (computed once: erfc is the render's dearest step)."""
    global _KINK_TABLE
    if _KINK_TABLE is None:
        from scipy.special import erfc

        a = np.arange(0.0, 8.0 + 2 * KINK_TABLE_STEP, KINK_TABLE_STEP)
        f = np.exp(-0.5 * a * a) / np.sqrt(2.0 * np.pi) - 0.5 * a * erfc(a / np.sqrt(2.0))
        _KINK_TABLE = f.astype(np.float32)
    return _KINK_TABLE


def _smoothed_kink(t: np.ndarray, s: np.ndarray) -> np.ndarray:
    """What a Gaussian (sigma s) adds to |t| at a kink, halved: s f(|t|/s), f(a) = phi(a) - a Phi(-a)
    (from the table, linear interpolation: error ~1e-8 of s)."""
    table = _kink_table()
    pos = np.minimum(np.abs(t) / s, np.float32(8.0)) * np.float32(1.0 / KINK_TABLE_STEP)
    i = pos.astype(np.int32)
    frac = pos - i
    return s * (table[i] + frac * (table[i + 1] - table[i]))


def _blurred_box_square_wave(x: np.ndarray, width: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Mean of the square wave under a box of ``width`` convolved with a Gaussian of sigma ``s`` (exact).

    The box's mean is a difference of the triangle wave (:func:`_triangle`);
    the Gaussian rounds each of its kinks (at the integers, slope +-1 -> -+1)
    by 2 (-1)^m :func:`_smoothed_kink`: the nearest kink, and its neighbours
    where the blur exceeds WIDE_BLUR_SQUARES (farther ones are 1.5 squares
    away, where a kernel under 0.3 square is nil).
    """
    s = np.maximum(s, np.float32(1e-6))
    half = 0.5 * width
    wide = s > WIDE_BLUR_SQUARES  # the next kinks matter only under a blur this wide (of a square)
    total = np.zeros_like(x)
    for sign, y in ((1.0, x + half), (-1.0, x - half)):
        m0 = np.round(y)
        ty = _triangle(y) + 2.0 * (1.0 - 2.0 * _mod2(m0)) * _smoothed_kink(y - m0, s)
        if wide.any():
            for dm in (-1.0, 1.0):
                m = m0[wide] + dm
                ty[wide] += 2.0 * (1.0 - 2.0 * _mod2(m)) * _smoothed_kink(y[wide] - m, s[wide])
        total = total + sign * ty
    return total / width


def _nonzero_window(img: np.ndarray) -> tuple[slice, slice] | None:
    """The rows and columns spanning every non-zero pixel of ``img`` (None: all are 0)."""
    rows, cols = np.flatnonzero(img.any(axis=1)), np.flatnonzero(img.any(axis=0))
    if not rows.size:
        return None
    return slice(int(rows[0]), int(rows[-1]) + 1), slice(int(cols[0]), int(cols[-1]) + 1)


def _reaches_inner_edge(mask: np.ndarray, window: tuple[slice, slice], shape: tuple[int, int]) -> bool:
    """Whether ``mask`` (``window`` of an image of ``shape``) is set on an edge of the window that is not the image's."""
    (r, c), (h, w) = window, shape
    return bool((r.start > 0 and mask[0].any()) or (r.stop < h and mask[-1].any())
                or (c.start > 0 and mask[:, 0].any()) or (c.stop < w and mask[:, -1].any()))


def _box_inside(x: np.ndarray, width: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Fraction of [x - width/2, x + width/2] inside [lo, hi] (exact)."""
    half = 0.5 * width
    return np.clip((np.minimum(x + half, hi) - np.maximum(x - half, lo)) / width, 0.0, 1.0)


@dataclass(frozen=True)
class Surface:
    """Each pixel's ray on a board: board coordinates and footprint (squares), front-facing mask, depth."""

    bx: np.ndarray
    by: np.ndarray
    wx: np.ndarray
    wy: np.ndarray
    facing: np.ndarray
    depth: np.ndarray  # along the optical axis per unit of normalized ray, i.e. z_cam (mm)
    sx: np.ndarray | None = None  # |d bx / d(u, v)|: a 1-px Gaussian's sigma along board x (squares)
    sy: np.ndarray | None = None


class BoardRenderer:
    """Renders 8-bit grey images of ``board`` through ``intrinsics``.

    Parameters
    ----------
    board : the chessboard; corner (r, c) at (c s, r s, 0) mm (SPEC 2). The
        outer squares extend one square beyond the inner corners.
    intrinsics : camera model; the image size is ``intrinsics.image_size``.
    margin_squares : white paper around the checker area, in squares.
    lighting : grey levels, blur, vignetting, texture, shot noise.
    noise_grey : Gaussian read noise sigma in grey levels (0 = none).
    lens : a :class:`lps_gui.core.truth.realism.LensMisfit`: the true lens's terms beyond ``intrinsics`` (None: none).
    """

    def __init__(
        self,
        board: Board,
        intrinsics: CameraIntrinsics,
        margin_squares: float = 1.0,
        lighting: Lighting | None = None,
        noise_grey: float = 0.0,
        texture_seed: int = 1,
        rays: tuple[np.ndarray, ...] | None = None,
        lens: Any = None,
    ) -> None:
        self.board = board
        self.intrinsics = intrinsics
        self.margin_squares = float(margin_squares)
        self.lighting = lighting or Lighting()
        self.noise_grey = float(noise_grey)
        self.rays = rays if rays is not None else camera_rays(intrinsics, lens)  # shared by renderers of one camera
        self._x, self._y, self._j00, self._j01, self._j10, self._j11 = self.rays
        w, h = intrinsics.image_size
        self._gain = None
        if self.lighting.vignetting:
            r2 = ((np.arange(w) - intrinsics.cx) / (0.5 * w))[None, :] ** 2 + (
                (np.arange(h) - intrinsics.cy) / (0.5 * h)
            )[:, None] ** 2
            self._gain = (1.0 - self.lighting.vignetting * r2 / 2.0).astype(np.float32)
        self._edge_weight = None
        if self.lighting.blur_edge_px > self.lighting.blur_px:  # 0 at the principal point, 1 at the farthest corner
            r2 = ((np.arange(w) - intrinsics.cx) ** 2)[None, :] + ((np.arange(h) - intrinsics.cy) ** 2)[:, None]
            self._edge_weight = (r2 / r2.max()).astype(np.float32)
        self._texture = None
        if self.lighting.texture:
            rng = np.random.default_rng(texture_seed)
            tex = rng.normal(0.0, 1.0, size=(board.rows + 3, board.cols + 3)).astype(np.float32)
            self._texture = cv2.resize(tex, None, fx=16, fy=16, interpolation=cv2.INTER_CUBIC)

    @property
    def image_size(self) -> tuple[int, int]:
        return self.intrinsics.image_size

    def render_float(self, R_cam_board: np.ndarray, t_cam_board: np.ndarray) -> np.ndarray:
        """Noise-free irradiance in grey levels, float32 shape (H, W).

        A lens blurs the scene *before* the pixels integrate it. Blurring the
        pixel-integrated image instead (a discrete Gaussian on the box-filtered
        render) is not the same: the corners it makes are pulled by ~0.01 px
        towards a sub-pixel phase, a pattern that does not average over a board
        (it leaned a planar gantry's squareness, issue 35). So the checker's
        modulation, which alone makes the corners, is blurred analytically
        (:func:`_blurred_box_square_wave`: pixel box and lens Gaussian together),
        and only the slowly varying rest (paper, board outline, background) takes
        the discrete blur.
        """
        lt = self.lighting
        if not self.analytic_blur:
            surface = self.surface(R_cam_board, t_cam_board)
            board_val, paper = self.shade(surface)
            img = lt.background + paper * (board_val - lt.background)
            img = np.where(surface.facing, img, lt.background).astype(np.float32)
            return self.optics(img)
        w, h = self.intrinsics.image_size
        window = self._paper_window(R_cam_board, t_cam_board)
        img = None if window is None else self._analytic_render(R_cam_board, t_cam_board, window)
        if img is None:  # no window, or the board reached its edge: the whole frame
            img = self._analytic_render(R_cam_board, t_cam_board, (slice(0, h), slice(0, w)))
        return img

    def _analytic_render(self, R_cam_board: np.ndarray, t_cam_board: np.ndarray,
                         window: tuple[slice, slice]) -> np.ndarray | None:
        """:meth:`render_float`'s analytic path, the board's surface and checker computed on ``window`` (rows,
        columns) only: outside it is background, as the whole frame's render has it there. None when the paper or
        its blurred contrast reaches the window's edge inside the image (the window is too small: the caller
        renders the whole frame), so the image is the whole frame's, bit for bit, at a fraction of the cost."""
        lt = self.lighting
        w, h = self.intrinsics.image_size
        surface = self.surface(R_cam_board, t_cam_board, window)
        board_val, paper, depth = self._plain_layers(surface)
        if _reaches_inner_edge(surface.facing & (paper != 0), window, (h, w)):
            return None
        base = np.full((h, w), lt.background, np.float32)
        base[window] = np.where(surface.facing, lt.background + paper * (board_val - lt.background), lt.background)
        full_depth = np.zeros((h, w), np.float32)
        full_depth[window] = np.where(surface.facing, depth, 0.0)
        blurred_depth = self.optics(full_depth, vignette=False)
        # the checker counts only where the blurred contrast is not 0 (0 * checker elsewhere)
        checker = np.zeros((h, w), np.float32)
        contrast = _nonzero_window(blurred_depth)
        if contrast is not None:
            if any(c.start < o.start or c.stop > o.stop for c, o in zip(contrast, window)):
                return None
            checker[contrast] = self.checker(surface, tuple(slice(c.start - o.start, c.stop - o.start)
                                                            for c, o in zip(contrast, window)))
        return self.compose(base, blurred_depth, checker, depth_blurred=True)

    PAPER_WINDOW_STEP = 8  # px between the rays of the coarse pass that finds the board's part of the frame
    PAPER_WINDOW_HORIZON = 0.2  # a ray this much nearer the board plane's horizon than another: the whole frame

    def _paper_window(self, R_cam_board: np.ndarray, t_cam_board: np.ndarray) -> tuple[slice, slice] | None:
        """The rows and columns the board's paper covers, from a coarse pass (every PAPER_WINDOW_STEP-th ray and
        the frame's edges) on the flat board: the paper widened by twice the largest pixel footprint and two squares,
        padded by the step and the lens blur's reach. None (render the whole frame) when no ray hits it, or when the
        board plane's horizon is near the frame (a pixel's footprint grows without bound there: a pixel far from the
        paper can still cover some of it). A guess: :meth:`_analytic_render` checks the paper ends inside it.
        """
        step = self.PAPER_WINDOW_STEP
        w, h = self.intrinsics.image_size
        grid = np.ix_(np.r_[0:h:step, h - 1], np.r_[0:w:step, w - 1])
        s = self.board.square_mm
        R = np.asarray(R_cam_board, dtype=float).reshape(3, 3)
        t = np.asarray(t_cam_board, dtype=float).ravel()
        G = np.linalg.inv(np.column_stack([R[:, 0] * s, R[:, 1] * s, t]))
        x, y = self._x[grid], self._y[grid]
        wz = G[2, 0] * x + G[2, 1] * y + G[2, 2]
        if not wz.min() > self.PAPER_WINDOW_HORIZON * wz.max():
            return None
        inv_w = 1.0 / wz
        bx = (G[0, 0] * x + G[0, 1] * y + G[0, 2]) * inv_w
        by = (G[1, 0] * x + G[1, 1] * y + G[1, 2]) * inv_w
        j00, j01, j10, j11 = (j[grid] for j in (self._j00, self._j01, self._j10, self._j11))
        a00, a01 = (G[0, 0] - bx * G[2, 0]) * inv_w, (G[0, 1] - bx * G[2, 1]) * inv_w
        a10, a11 = (G[1, 0] - by * G[2, 0]) * inv_w, (G[1, 1] - by * G[2, 1]) * inv_w
        footprint = max(float(np.max(np.abs(a00 * j00 + a01 * j10) + np.abs(a00 * j01 + a01 * j11))),
                        float(np.max(np.abs(a10 * j00 + a11 * j10) + np.abs(a10 * j01 + a11 * j11))))
        m = 1.0 + self.margin_squares + 2.0 + 2.0 * footprint
        hit = (bx > -m) & (bx < self.board.cols + m) & (by > -m) & (by < self.board.rows + m)
        rows, cols = grid[0].ravel()[hit.any(axis=1)], grid[1].ravel()[hit.any(axis=0)]
        if not rows.size:
            return None
        pad = step + int(np.ceil(4.0 * max(self.lighting.blur_px, self.lighting.blur_edge_px))) + 2
        return (slice(max(int(rows.min()) - pad, 0), min(int(rows.max()) + pad + 1, h)),
                slice(max(int(cols.min()) - pad, 0), min(int(cols.max()) + pad + 1, w)))

    @property
    def analytic_blur(self) -> bool:
        """Whether the checker is blurred analytically (:meth:`render_float`): antialiased, blurred, no texture."""
        lt = self.lighting
        return bool(lt.antialias and lt.blur_px > 0 and self._texture is None)

    def layers(self, surface: "Surface") -> tuple[np.ndarray, ...]:
        """The board without its checker (grey levels), the paper fraction, the checker's half contrast where
        it is printed, and the checker blurred by pixel and lens (+1 black, -1 white): the scene is
        ``background + paper (board - background) - depth checker``."""
        return (*self._plain_layers(surface), self.checker(surface))

    def _plain_layers(self, surface: Surface) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`layers` without the checker: the board's grey level, the paper fraction, the checker's half contrast."""
        lt = self.lighting
        inside, paper = self._masks(surface)
        mid, half = 0.5 * (lt.white + lt.black), 0.5 * (lt.white - lt.black)
        board_val = lt.white + inside * (mid - lt.white)
        return board_val, paper, paper * inside * half

    def checker(self, surface: Surface, window: tuple[slice, slice] = (slice(None), slice(None))) -> np.ndarray:
        """The checker blurred by pixel and lens (+1 black, -1 white) on ``window`` (rows, columns) of ``surface``."""
        b = np.float32(self.lighting.blur_px)
        return (_blurred_box_square_wave(surface.bx[window], surface.wx[window], b * surface.sx[window])
                * _blurred_box_square_wave(surface.by[window], surface.wy[window], b * surface.sy[window]))

    def compose(self, base: np.ndarray, depth: np.ndarray, checker: np.ndarray,
                depth_blurred: bool = False) -> np.ndarray:
        """The lens on a scene in layers (:meth:`layers`): the slowly varying base and the checker's contrast
        take the discrete blur (``depth_blurred``: the contrast already has it), the checker itself is already
        blurred; vignetting dims the whole."""
        blurred = depth if depth_blurred else self.optics(depth, vignette=False)
        img = self.optics(base, vignette=False) - blurred * checker.astype(np.float32)
        if self._gain is not None:
            img *= self._gain
        return img.astype(np.float32)

    def surface(self, R_cam_board: np.ndarray, t_cam_board: np.ndarray,
                window: tuple[slice, slice] = (slice(None), slice(None))) -> "Surface":
        """Where each pixel's ray meets the board (in squares), its footprint there and its depth.

        ``window`` (rows, columns) restricts the work to part of the image (a target's bounding box).
        """
        s = self.board.square_mm
        R = np.asarray(R_cam_board, dtype=float).reshape(3, 3)
        t = np.asarray(t_cam_board, dtype=float).ravel()
        # normalized image point ~ [r1 r2 t] (X, Y, 1): invert for board coords in squares
        H = np.column_stack([R[:, 0] * s, R[:, 1] * s, t])
        G = np.linalg.inv(H).astype(np.float32)  # normalized -> board (squares), homogeneous
        x, y = self._x[window], self._y[window]
        j00, j01, j10, j11 = (j[window] for j in (self._j00, self._j01, self._j10, self._j11))
        wz = G[2, 0] * x + G[2, 1] * y + G[2, 2]
        facing = wz > 0  # rays that hit the board plane in front of the camera
        inv_w = 1.0 / np.where(facing, wz, 1.0)
        bx = (G[0, 0] * x + G[0, 1] * y + G[0, 2]) * inv_w
        by = (G[1, 0] * x + G[1, 1] * y + G[1, 2]) * inv_w
        if self.board.warp_mm is not None:
            bx, by = self._on_warped_surface(R, t, bx, by, x, y)
        # d(bx, by) / d(x', y') of the homography, chained with d(x', y') / d(u, v)
        a00 = (G[0, 0] - bx * G[2, 0]) * inv_w
        a01 = (G[0, 1] - bx * G[2, 1]) * inv_w
        a10 = (G[1, 0] - by * G[2, 0]) * inv_w
        a11 = (G[1, 1] - by * G[2, 1]) * inv_w
        bxu, bxv, byu, byv = a00 * j00 + a01 * j10, a00 * j01 + a01 * j11, a10 * j00 + a11 * j10, a10 * j01 + a11 * j11
        wx, wy = np.abs(bxu) + np.abs(bxv), np.abs(byu) + np.abs(byv)
        if not self.lighting.antialias:
            wx[:], wy[:] = 1e-4, 1e-4
        np.maximum(wx, 1e-4, out=wx)
        np.maximum(wy, 1e-4, out=wy)
        return Surface(bx, by, wx, wy, facing, inv_w, np.hypot(bxu, bxv), np.hypot(byu, byv))

    def _masks(self, surface: "Surface") -> tuple[np.ndarray, np.ndarray]:
        """Fractions of each pixel inside the checker area and on the paper."""
        bx, by, wx, wy = surface.bx, surface.by, surface.wx, surface.wy
        inside = _box_inside(bx, wx, -1.0, self.board.cols) * _box_inside(by, wy, -1.0, self.board.rows)
        m = self.margin_squares
        paper = _box_inside(bx, wx, -1.0 - m, self.board.cols + m) * _box_inside(by, wy, -1.0 - m, self.board.rows + m)
        return inside, paper

    def shade(self, surface: "Surface") -> tuple[np.ndarray, np.ndarray]:
        """The board's grey level at each pixel and the fraction of the pixel the paper covers."""
        bx, by, wx, wy = surface.bx, surface.by, surface.wx, surface.wy
        # squares span [-1, cols] x [-1, rows]; square [0,1)x[0,1) is black
        checker = _box_square_wave(bx, wx) * _box_square_wave(by, wy)  # +1 black, -1 white
        inside, paper = self._masks(surface)
        m = self.margin_squares
        lt = self.lighting
        mid, half = 0.5 * (lt.white + lt.black), 0.5 * (lt.white - lt.black)
        board_val = (lt.white + inside * (mid - half * checker - lt.white)).astype(np.float32)
        if self._texture is not None:
            tex = cv2.remap(self._texture, (bx + 1.0 + m) * 16, (by + 1.0 + m) * 16, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            board_val *= 1.0 + lt.texture * tex
        return board_val, paper

    def optics(self, img: np.ndarray, vignette: bool = True) -> np.ndarray:
        """Blur and vignetting of the lens, applied to the whole scene's irradiance."""
        if self._edge_weight is not None:  # two blurs blended by r^2: symmetric about every corner point
            sharp = cv2.GaussianBlur(img, (0, 0), self.lighting.blur_px) if self.lighting.blur_px > 0 else img
            soft = cv2.GaussianBlur(img, (0, 0), self.lighting.blur_edge_px)
            img = sharp + self._edge_weight * (soft - sharp)
        elif self.lighting.blur_px > 0:
            img = cv2.GaussianBlur(img, (0, 0), self.lighting.blur_px)
        if vignette and self._gain is not None:
            img *= self._gain
        return img

    def _on_warped_surface(
        self, R: np.ndarray, t: np.ndarray, bx: np.ndarray, by: np.ndarray, x: np.ndarray, y: np.ndarray,
        iterations: int = 4,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Where each pixel's ray meets the bowed board (Board.warp_mm), board squares.

        The ray meets the plane z = h at a point that moves with h; starting
        from the flat board's hit, h is set to the surface height there and
        the ray re-intersected. The surface slope is ~1e-2, so each pass
        shrinks the error ~100-fold and four passes are exact in float32.
        The footprint widths keep the flat board's values (a 1e-2 change in
        the anti-aliasing width, symmetric about every corner).
        """
        s = self.board.square_mm
        c = -R.T @ t  # camera centre in the board frame, mm
        d = [np.float32(R[0, k]) * x + np.float32(R[1, k]) * y + np.float32(R[2, k]) for k in range(3)]
        dz = np.where(np.abs(d[2]) > 1e-9, d[2], np.float32(1e-9))
        for _ in range(iterations):
            h = self.board.warp_z(np.stack([bx * s, by * s], axis=-1)).astype(np.float32)
            lam = (h - np.float32(c[2])) / dz
            bx = (np.float32(c[0]) + lam * d[0]) / np.float32(s)
            by = (np.float32(c[1]) + lam * d[1]) / np.float32(s)
        return bx, by

    def render(
        self,
        R_cam_board: np.ndarray,
        t_cam_board: np.ndarray,
        rng: np.random.Generator | None = None,
    ) -> np.ndarray:
        """An 8-bit grey image, shape (H, W), of the board at pose (R_cam_board, t_cam_board mm).

        Noise (Gaussian ``noise_grey`` and shot noise) is drawn from ``rng``;
        without an ``rng`` the image is noise-free (only quantized).
        """
        return self.quantize(self.render_float(R_cam_board, t_cam_board), rng)

    def quantize(self, img: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """Sensor noise (from ``rng``; none without one) and 8-bit quantization of an irradiance image."""
        if rng is not None and (self.noise_grey > 0 or self.lighting.shot_gain > 0):
            noise = rng.standard_normal(size=img.shape, dtype=np.float32)
            if self.lighting.shot_gain > 0:
                sigma = np.sqrt(self.noise_grey**2 + self.lighting.shot_gain * np.maximum(img, 0.0))
                img += noise * sigma
            else:
                img += noise * np.float32(self.noise_grey)
        return np.clip(img + 0.5, 0, 255).astype(np.uint8)
