"""A simulated scene for light fields (issue 38): textured planes at known depths and one slanted plane.

The light field of a stage is checked on a scene whose geometry is known exactly: planes parallel to the
motion (so each has one depth along the whole travel, and its disparity is linear in the camera's position)
at a few depths around the board's, one slanted plane (a depth ramp, what an EPI shows as bent lines
elsewhere), and a backdrop that fills the rest of the view. Every plane is a rectangle with its own
texture seed; the renderer (``camera/render_scene.py``) draws them through the rig's camera model, and
:func:`scene_points` gives points on them whose projections the epipolar check follows (the "known scene
points" of the issue). World frame = the board frame of SPEC 2, mm.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.models.lps_model import unit
from lps_gui.core.truth.rig import Rig

TEXEL_PX = 0.6  # texel size in pixels at the plane's depth
DEPTH_FRACTIONS = (0.6, 0.8, 1.0)  # fronto-parallel planes at these fractions of the board's distance
BACKDROP_FRACTION = 1.5
SLANT_FRACTIONS = (0.7, 1.25)  # the slanted plane's depth at its left and right edge


@dataclass(frozen=True)
class ScenePlane:
    """A textured rectangle: centre ``origin`` (3,) mm, unit in-plane axes ``e1``, ``e2`` (3,), half sizes mm.

    ``depth_mm``: the distance of a plane parallel to the motion from the camera's path (None when slanted).
    """

    name: str
    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    half_mm: tuple[float, float]
    texture_seed: int
    texel_mm: float  # the texture's grain: one texel is about 0.6 px where the camera sees the plane
    depth_mm: float | None = None

    @property
    def normal(self) -> np.ndarray:
        return unit(np.cross(self.e1, self.e2))

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "origin_mm": self.origin.tolist(), "e1": self.e1.tolist(), "e2": self.e2.tolist(),
                "half_mm": list(self.half_mm), "texture_seed": self.texture_seed, "texel_mm": self.texel_mm,
                "depth_mm": self.depth_mm}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ScenePlane":
        depth = d.get("depth_mm")
        return cls(str(d["name"]), np.asarray(d["origin_mm"], float), np.asarray(d["e1"], float),
                   np.asarray(d["e2"], float), (float(d["half_mm"][0]), float(d["half_mm"][1])),
                   int(d["texture_seed"]), float(d["texel_mm"]), None if depth is None else float(depth))


@dataclass(frozen=True)
class Scene:
    """The planes of a scene, nearest first (the renderer keeps the nearest hit of every ray anyway)."""

    planes: tuple[ScenePlane, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"planes": [p.to_dict() for p in self.planes]}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Scene":
        return cls(tuple(ScenePlane.from_dict(p) for p in d["planes"]))


def scene_for_rig(rig: Rig, travel: np.ndarray, seed: int = 0) -> Scene:
    """The standard scene in front of ``rig``'s camera over commanded positions ``travel`` (K,) or (K, 2) mm.

    Depths are fractions of the board's distance from the camera, measured along the normal of the
    motion (line) or of the plane of motion (gantry), so each fronto-parallel plane keeps its depth over
    the travel. The three planes sit side by side across the view of the middle camera, the slanted
    plane below them, the backdrop behind everything and wide enough for the views at both ends.
    """
    t = np.asarray(travel, dtype=float)
    R = rig.R_cam_board
    if rig.planar:
        E = rig.axes_board
        mid = 0.5 * (t.min(axis=0) + t.max(axis=0))
        C = rig.C0_board + E[:, :2] @ mid
        x_dir, normal = E[:, 0], unit(E[:, 2] * np.sign(E[:, 2] @ R[2]))
        span = float(np.ptp(t[:, 0])) + float(np.ptp(t[:, 1]))
    else:
        u = rig.u_board
        mid = 0.5 * (t.min() + t.max())
        C = rig.C0_board + mid * u
        axis = R[2]
        normal = unit(axis - (axis @ u) * u)
        x_dir, span = u, float(np.ptp(t))
    x_dir = x_dir * np.sign(x_dir @ R[0])  # image right
    down = unit(np.cross(normal, x_dir))
    board_depth = float((rig.board.centre_mm() - C) @ normal)
    w, h = rig.intrinsics.image_size
    tan_x, tan_y = 0.5 * w / rig.intrinsics.fx, 0.5 * h / rig.intrinsics.fy
    texel = TEXEL_PX / rig.intrinsics.fx  # mm of texel per mm of depth
    planes = []
    for k, frac in enumerate(DEPTH_FRACTIONS):  # three columns of the upper two thirds of the view
        Z = frac * board_depth
        col_w = 2 * tan_x * Z / len(DEPTH_FRACTIONS)
        cx = (-tan_x * Z) + (k + 0.5) * col_w
        cy = -tan_y * Z / 3.0
        planes.append(ScenePlane(f"plane_{int(round(100 * frac))}", C + Z * normal + cx * x_dir + cy * down,
                                 x_dir, down, (0.45 * col_w, 0.62 * tan_y * Z), seed * 100 + k + 1, texel * Z, Z))
    z0, z1 = (f * board_depth for f in SLANT_FRACTIONS)
    zm, half_w = 0.5 * (z0 + z1), 0.9 * tan_x * 0.5 * (z0 + z1)
    along = unit(2 * half_w * x_dir + (z1 - z0) * normal)  # the ramp rises in depth from left to right
    half_len = 0.5 * float(np.hypot(2 * half_w, z1 - z0))
    planes.append(ScenePlane("slanted", C + zm * normal + 0.68 * tan_y * zm * down, along, down,
                             (half_len, 0.25 * tan_y * zm), seed * 100 + 9, texel * zm))
    Zb = BACKDROP_FRACTION * board_depth
    planes.append(ScenePlane("backdrop", C + Zb * normal, x_dir, down,
                             (1.2 * tan_x * Zb + span, 1.2 * tan_y * Zb + span), seed * 100 + 10, texel * Zb, Zb))
    return Scene(tuple(planes))


def ray_hits(scene: Scene, centre: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest plane each ray meets: its index (-1: none) and the ray parameter there.

    ``centre`` (3,) mm, ``dirs`` (..., 3) world directions (any length); the parameter multiplies ``dirs``.
    """
    d = np.asarray(dirs, dtype=float)
    best = np.full(d.shape[:-1], np.inf)
    which = np.full(d.shape[:-1], -1, dtype=int)
    for k, p in enumerate(scene.planes):
        n = p.normal
        denom = d @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = ((p.origin - centre) @ n) / denom
        X = centre + lam[..., None] * d - p.origin
        inside = (np.abs(X @ p.e1) <= p.half_mm[0]) & (np.abs(X @ p.e2) <= p.half_mm[1])
        hit = inside & (lam > 0) & (lam < best)
        best = np.where(hit, lam, best)
        which = np.where(hit, k, which)
    return which, best


def scene_points(scene: Scene, per_axis: tuple[int, int] = (9, 5)) -> tuple[np.ndarray, np.ndarray]:
    """A grid of points inside every plane but the backdrop: world points (N, 3) mm and their plane index (N,)."""
    pts, owner = [], []
    a = np.linspace(-0.8, 0.8, per_axis[0])
    b = np.linspace(-0.7, 0.7, per_axis[1])
    A, B = np.meshgrid(a, b)
    for k, p in enumerate(scene.planes):
        if p.name == "backdrop":
            continue
        P = p.origin + (A.ravel() * p.half_mm[0])[:, None] * p.e1 + (B.ravel() * p.half_mm[1])[:, None] * p.e2
        pts.append(P)
        owner.append(np.full(len(P), k))
    return np.concatenate(pts), np.concatenate(owner)


def visible_points(scene: Scene, centre: np.ndarray, points: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Which ``points`` of plane ``owner`` a camera at ``centre`` sees (no nearer plane in the way), (N,) bool."""
    which, _ = ray_hits(scene, np.asarray(centre, float), np.asarray(points, float) - centre)
    return which == owner
