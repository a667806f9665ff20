"""Render a row or constellation of ChArUco targets (SPEC 13) as the camera sees it.

Each target's checker is the exact-area render of :mod:`lps_gui.camera.render`
(corners stay unbiased); its markers are sampled from OpenCV's own drawing of
the board (so the ids are the ones the detector expects), as a darkness mask
inside the white squares: markers only have to be read, their edges never
enter a corner's estimate. Where targets overlap in the image, the nearest
wins (a two-depth constellation). One lens blur and one sensor noise apply to
the whole scene.
"""
from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from lps_gui.camera.charuco import aruco_board
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.geometry.target_rig import TargetLayout
from lps_gui.core.geometry.targets import Target

TEXELS_PER_SQUARE = 96


def marker_mask(target: Target, texels: int = TEXELS_PER_SQUARE) -> np.ndarray:
    """Darkness (0..1) of the markers over the target's squares, float32 ((rows+1) t, (cols+1) t); 0 off-marker."""
    b = target.board
    size = ((b.cols + 1) * texels, (b.rows + 1) * texels)
    img = aruco_board(b, target.first_marker).generateImage(size, marginSize=0).astype(np.float32) / 255.0
    r, c = np.mgrid[0: size[1], 0: size[0]] // texels
    white_square = (r + c) % 2 == 1  # the top-left square is black, as in the analytic checker
    return np.where(white_square, 1.0 - img, 0.0).astype(np.float32)


class TargetsRenderer:
    """8-bit grey images of a :class:`TargetLayout` seen through ``intrinsics`` from camera poses (R, t) of the world."""

    def __init__(self, layout: TargetLayout, intrinsics: CameraIntrinsics, lighting: Lighting | None = None,
                 noise_grey: float = 0.0, margin_squares: float = 0.5, lens: Any = None) -> None:
        self.layout = layout
        self.intrinsics = intrinsics
        self.lighting = lighting or Lighting()
        first = BoardRenderer(layout.targets[0].board, intrinsics, margin_squares, self.lighting, noise_grey, lens=lens)
        self._renderers = [first] + [BoardRenderer(t.board, intrinsics, margin_squares, self.lighting, noise_grey,
                                                   rays=first.rays) for t in layout.targets[1:]]
        self.margin_squares = margin_squares
        self._masks = [marker_mask(t) for t in layout.targets]

    @property
    def image_size(self) -> tuple[int, int]:
        return self.intrinsics.image_size

    def render_float(self, R: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Noise-free irradiance (H, W) float32 of the scene from camera pose x_cam = R X_w + t."""
        lt = self.lighting
        w, h = self.intrinsics.image_size
        img = np.full((h, w), lt.background, np.float32)
        nearest = np.full((h, w), np.inf, np.float32)
        analytic = self._renderers[0].analytic_blur  # the checkers blurred as by the lens (BoardRenderer.render_float)
        depth_img = np.zeros((h, w), np.float32)
        checker_img = np.zeros((h, w), np.float32)
        for j, (renderer, mask) in enumerate(zip(self._renderers, self._masks)):
            R_j = R @ self.layout.Q[j]
            t_j = R @ self.layout.p[j] + t
            window = self._window(j, R_j, t_j)
            if window is None:
                continue
            surface = renderer.surface(R_j, t_j, window)
            if analytic:
                value, paper, depth, checker = renderer.layers(surface)
            else:
                value, paper = renderer.shade(surface)
            hit = surface.facing & (paper > 0) & (surface.depth < nearest[window])
            if not hit.any():
                continue
            k = TEXELS_PER_SQUARE
            dark = cv2.remap(mask, (surface.bx + 1.0) * k - 0.5, (surface.by + 1.0) * k - 0.5, cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
            value = value + dark * np.float32(lt.black - lt.white)
            scene = lt.background + paper * (value - lt.background)
            img[window] = np.where(hit, scene, img[window])
            nearest[window] = np.where(hit, surface.depth, nearest[window])
            if analytic:
                depth_img[window] = np.where(hit, depth, depth_img[window])
                checker_img[window] = np.where(hit, checker, checker_img[window])
        if analytic:
            return self._renderers[0].compose(img, depth_img, checker_img)
        return self._renderers[0].optics(img)

    def _window(self, j: int, R_j: np.ndarray, t_j: np.ndarray) -> tuple[slice, slice] | None:
        """The image rows and columns target j's paper can cover (its projected outline, padded), or None."""
        b = self.layout.targets[j].board
        m = 1.0 + self.margin_squares
        lo, hi = -m * b.square_mm, (np.array([b.cols, b.rows]) - 1 + m) * b.square_mm
        edge = np.linspace(0.0, 1.0, 25)
        xs = np.r_[lo + edge * (hi[0] - lo), np.full(25, hi[0]), hi[0] - edge * (hi[0] - lo), np.full(25, lo)]
        ys = np.r_[np.full(25, lo), lo + edge * (hi[1] - lo), np.full(25, hi[1]), hi[1] - edge * (hi[1] - lo)]
        outline = np.stack([xs, ys, np.zeros_like(xs)], axis=1) @ R_j.T + t_j
        w, h = self.intrinsics.image_size
        if np.all(outline[:, 2] <= 0):
            return None
        if np.any(outline[:, 2] <= 0):
            return (slice(None), slice(None))  # the target crosses the camera's plane: no safe box
        uv = project(outline, self.intrinsics).uv
        pad = 4 + 3 * self.lighting.blur_px
        u0, v0 = np.floor(uv.min(axis=0) - pad).astype(int)
        u1, v1 = np.ceil(uv.max(axis=0) + pad).astype(int)
        u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, w), min(v1, h)
        if u0 >= u1 or v0 >= v1:
            return None
        return (slice(v0, v1), slice(u0, u1))

    def render(self, R: np.ndarray, t: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        return self._renderers[0].quantize(self.render_float(R, t), rng)
