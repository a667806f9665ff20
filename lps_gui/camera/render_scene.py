"""Render the light-field scene (``core/truth/scene.py``) as the simulated camera sees the board.

Same camera model, same optics and the same sensor as :class:`BoardRenderer`: every pixel's undistorted
ray (computed once per camera), the nearest plane it meets, that plane's texture there, then the lens blur,
vignetting, noise and 8-bit quantization of the board renders (this class inherits them). Textures are
band-limited noise at two scales plus scattered discs (features for matchers), sampled with bilinear
interpolation: one texel is about 0.6 px at the plane's depth, and the texture carries nothing finer than
about 3.5 texels (2 px), so point sampling at the pixel centres does not alias.
"""
from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.truth.scene import Scene

MAX_TEXELS = 4096


@lru_cache(maxsize=16)
def _texture(seed: int, shape: tuple[int, int]) -> np.ndarray:
    """Grey levels (float32) of a plane's texture: smooth blotches, fine grain and discs, 30..230."""
    rng = np.random.default_rng(seed)
    h, w = shape
    fine = cv2.GaussianBlur(rng.standard_normal((h, w)).astype(np.float32), (0, 0), 3.5)
    coarse = cv2.GaussianBlur(rng.standard_normal((h, w)).astype(np.float32), (0, 0), 12.0)
    img = fine / (fine.std() + 1e-6) + 1.5 * coarse / (coarse.std() + 1e-6)
    n_discs = max(8, (h * w) // 4000)
    discs = np.zeros((h, w), np.float32)
    for x, y, r, s in zip(rng.uniform(0, w, n_discs), rng.uniform(0, h, n_discs), rng.uniform(5, 14, n_discs),
                          rng.choice([-1.0, 1.0], n_discs)):
        cv2.circle(discs, (int(x), int(y)), int(r), float(s), -1, lineType=cv2.LINE_AA)
    img = (img - img.mean()) / (img.std() + 1e-6) + 3.0 * cv2.GaussianBlur(discs, (0, 0), 2.5)
    level = rng.uniform(90.0, 170.0)  # each plane its own brightness, so the planes read apart
    return np.clip(level + 28.0 * img, 30.0, 230.0).astype(np.float32)


class SceneRenderer(BoardRenderer):
    """Renders 8-bit grey images of a :class:`Scene` through ``intrinsics`` (the board renderer's optics)."""

    def __init__(self, scene: Scene, intrinsics: CameraIntrinsics, lighting: Lighting | None = None,
                 noise_grey: float = 0.0, rays: tuple[np.ndarray, ...] | None = None) -> None:
        from dataclasses import replace

        lighting = replace(lighting or Lighting(), texture=0.0)  # the planes carry their own textures
        super().__init__(board=None, intrinsics=intrinsics, lighting=lighting, noise_grey=noise_grey,  # type: ignore[arg-type]
                         rays=rays)
        self.scene = scene
        self._texel_mm = [max(p.texel_mm, 2 * max(p.half_mm) / MAX_TEXELS) for p in scene.planes]

    def render_float(self, R_cam_board: np.ndarray, t_cam_board: np.ndarray) -> np.ndarray:
        """Noise-free irradiance in grey levels, float32 (H, W): the nearest plane's texture at every pixel."""
        R = np.asarray(R_cam_board, dtype=float).reshape(3, 3)
        t = np.asarray(t_cam_board, dtype=float).ravel()
        x, y = self._x, self._y
        img = np.full(x.shape, self.lighting.background, np.float32)
        best = np.full(x.shape, np.inf, np.float32)
        for p, texel in zip(self.scene.planes, self._texel_mm):
            n_c = R @ p.normal  # the plane in camera coordinates: n_c . X = d
            d = float(n_c @ (R @ p.origin + t))
            denom = np.float32(n_c[0]) * x + np.float32(n_c[1]) * y + np.float32(n_c[2])
            with np.errstate(divide="ignore", invalid="ignore"):
                z = np.float32(d) / denom  # depth along the optical axis of each pixel's ray
            # hit point relative to the plane's origin, in world coordinates, projected on e1, e2
            r1, r2 = R @ p.e1, R @ p.e2  # plane axes in camera coordinates
            o = R @ p.origin + t
            a = z * (np.float32(r1[0]) * x + np.float32(r1[1]) * y + np.float32(r1[2])) - np.float32(o @ r1)
            b = z * (np.float32(r2[0]) * x + np.float32(r2[1]) * y + np.float32(r2[2])) - np.float32(o @ r2)
            hit = (z > 0) & (z < best) & (np.abs(a) <= p.half_mm[0]) & (np.abs(b) <= p.half_mm[1])
            if not hit.any():
                continue
            tw = int(np.ceil(2 * p.half_mm[0] / texel)) + 2
            th = int(np.ceil(2 * p.half_mm[1] / texel)) + 2
            tex = _texture(p.texture_seed, (th, tw))
            mx = ((a + np.float32(p.half_mm[0])) / np.float32(texel)).astype(np.float32)
            my = ((b + np.float32(p.half_mm[1])) / np.float32(texel)).astype(np.float32)
            val = cv2.remap(tex, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            img = np.where(hit, val, img)
            best = np.where(hit, z, best)
        return self.optics(img)
