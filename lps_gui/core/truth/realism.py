"""What a real rig has that the estimate's models do not: the simulator's realism switches (issue 35).

Off by default (``SimulationSpec.realism`` None: every earlier result stays
identical). On, a simulated session is what a careful user would really
record, so its truth comparison says whether the report's error bars hold on
real data:

- the true lens has OpenCV's rational (k4-k6) and thin-prism (s1-s4) terms
  the 5-coefficient Brown model cannot express (:class:`LensMisfit`); the
  estimate uses intrinsics calibrated from a separately rendered set, never
  the truth;
- each printed board or target is off its nominal scale and bowed
  (:meth:`Realism.printed_board`), drawn from the uncertainty the session
  declares (``square_mm_uncertainty_um``), so the budget can cover it;
- blur grows towards the image corners, vignetting and shot noise make the
  image noise vary over the frame (:meth:`Realism.lighting`).

Targets cut by the image border are the row simulations' own (the planner's
rule leaves the end views three-quarters covered). Pure math, no I/O.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.errors import InputError


@dataclass(frozen=True)
class LensMisfit:
    """The distortion terms beyond (k1, k2, p1, p2, k3): OpenCV's rational k4-k6 and thin-prism s1-s4.

    The full model (OpenCV's 12-coefficient one) on normalized coordinates (x, y), r2 = x^2 + y^2:
    radial = (1 + k1 r2 + k2 r4 + k3 r6) / (1 + k4 r2 + k5 r4 + k6 r6),
    x'' = x radial + 2 p1 x y + p2 (r2 + 2 x^2) + s1 r2 + s2 r4,
    y'' = y radial + p1 (r2 + 2 y^2) + 2 p2 x y + s3 r2 + s4 r4.
    """

    k4: float = 0.0
    k5: float = 0.0
    k6: float = 0.0
    s1: float = 0.0
    s2: float = 0.0
    s3: float = 0.0
    s4: float = 0.0

    def opencv_dist(self, intrinsics: CameraIntrinsics) -> np.ndarray:
        """The 12 coefficients cv2 takes: k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4."""
        return np.r_[intrinsics.dist[:5], self.k4, self.k5, self.k6, self.s1, self.s2, self.s3, self.s4]

    def distort(self, xy: np.ndarray, intrinsics: CameraIntrinsics) -> np.ndarray:
        """Pixels (..., 2) of normalized undistorted coordinates ``xy`` (..., 2) through the full lens."""
        k1, k2, p1, p2, k3 = intrinsics.dist
        x, y = xy[..., 0], xy[..., 1]
        r2 = x * x + y * y
        radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (self.k4 + r2 * (self.k5 + r2 * self.k6)))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + r2 * (self.s1 + self.s2 * r2)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + r2 * (self.s3 + self.s4 * r2)
        return np.stack([intrinsics.fx * xd + intrinsics.cx, intrinsics.fy * yd + intrinsics.cy], axis=-1)

    def project(self, x_cam: np.ndarray, intrinsics: CameraIntrinsics) -> np.ndarray:
        """Pixels (..., 2) of camera-frame points (..., 3) mm."""
        x_cam = np.asarray(x_cam, dtype=float)
        return self.distort(x_cam[..., :2] / x_cam[..., 2:3], intrinsics)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    def scaled_to(self, intrinsics: CameraIntrinsics, px: float) -> "LensMisfit":
        """These coefficients read as a shape on the image's half-diagonal (r = 1 at the corner), made into a lens
        for ``intrinsics`` whose terms move a corner point by about ``px`` times them (any camera, one misfit)."""
        w, h = intrinsics.image_size
        r = float(np.hypot(max(intrinsics.cx, w - intrinsics.cx) / intrinsics.fx,
                           max(intrinsics.cy, h - intrinsics.cy) / intrinsics.fy))
        a = px / (0.5 * (intrinsics.fx + intrinsics.fy))
        return LensMisfit(k4=a * self.k4 / r**3, k5=a * self.k5 / r**5, k6=a * self.k6 / r**7,
                          s1=a * self.s1 / r**2, s2=a * self.s2 / r**4, s3=a * self.s3 / r**2, s4=a * self.s4 / r**4)


# the shape of the misfit (rational terms mostly absorbed by k1-k3, thin-prism terms not at all) and the two sizes:
# the best 5-coefficient fit over the image leaves ~0.04 px RMS (on) or ~0.2 px (strong) on the small and the paper
# cameras (benchmarks/honesty.py --lens-misfit measures it)
LENS_SHAPE = LensMisfit(k4=1.0, k5=-0.5, k6=0.25, s1=0.6, s2=-0.4, s3=-0.4, s4=0.3)
MILD_LENS_PX, STRONG_LENS_PX = 0.8, 4.0


@dataclass(frozen=True)
class Realism:
    """The realism switches of a simulated session (one spec field turns all on)."""

    lens_px: float = MILD_LENS_PX  # size of the lens misfit's terms at the image corner (LensMisfit.scaled_to)
    lens_shape: LensMisfit = LENS_SHAPE
    print_scale_ppm: float = 10.0  # 1-sigma of each print's scale (the environment declares it)
    bow_mm: float = 0.1  # 1-sigma of each print's bow (bow_x, bow_y), mm
    blur_edge_px: float = 2.0  # blur sigma at the image corners (the centre keeps Lighting.blur_px)
    vignetting: float = 0.3  # relative fall-off at the corners: the image noise varies over the frame
    shot_gain: float = 0.5  # shot-noise variance per grey level

    def printed_board(self, board: Board, rng: np.random.Generator) -> Board:
        """The board as printed: its squares off by a scale drawn from ``print_scale_ppm``, bowed by ``bow_mm``."""
        scale = 1.0 + 1e-6 * self.print_scale_ppm * rng.standard_normal()
        bow = tuple(float(v) for v in self.bow_mm * rng.standard_normal(2))
        base = np.zeros(2) if board.warp_mm is None else np.asarray(board.warp_mm)
        return replace(board, square_mm=board.square_mm * scale, warp_mm=tuple((base + bow).tolist()))

    def printed_layout(self, layout: Any, rng: np.random.Generator) -> Any:
        """A row or constellation (TargetLayout) whose every target is printed by :meth:`printed_board`."""
        targets = tuple(replace(t, board=self.printed_board(t.board, rng)) for t in layout.targets)
        return replace(layout, targets=targets)

    def lens(self, intrinsics: CameraIntrinsics) -> LensMisfit:
        """The true lens's terms beyond the 5-coefficient model, for this camera."""
        return self.lens_shape.scaled_to(intrinsics, self.lens_px)

    def lighting(self) -> dict[str, float]:
        """The Lighting fields it sets (blur growing to the corners, vignetting, shot noise)."""
        return {"blur_edge_px": self.blur_edge_px, "vignetting": self.vignetting, "shot_gain": self.shot_gain}

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "lens_shape": self.lens_shape.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> "Realism | None":
        if not d:
            return None
        try:
            return cls(**{**d, "lens_shape": LensMisfit(**(d.get("lens_shape") or {}))})
        except TypeError as exc:
            raise InputError(f"session.json truth.realism: {exc}; start a new simulated session") from exc


REALISM = {"off": None, "on": Realism(), "strong": Realism(lens_px=STRONG_LENS_PX)}


def realism_named(name: str) -> Realism | None:
    """``--realism off|on|strong``: None, the mild lens misfit (~0.04 px) or the strong one (~0.2 px), with the rest."""
    if name not in REALISM:
        raise InputError(f"realism {name!r}: choose one of {', '.join(REALISM)}")
    return REALISM[name]


def brown_residual_px(intrinsics: CameraIntrinsics, lens: LensMisfit) -> tuple[float, float]:
    """RMS and max (px) of what the best 5-coefficient (Brown) lens leaves of ``lens`` over a 64 x 48 grid of
    the image: how much of the true lens the estimate's model cannot express."""
    import cv2
    from scipy.optimize import least_squares

    w, h = intrinsics.image_size
    u, v = np.meshgrid(np.linspace(0, w - 1, 64), np.linspace(0, h - 1, 48))
    uv = np.stack([u.ravel(), v.ravel()], -1)
    xy = cv2.undistortPoints(uv.reshape(-1, 1, 2), intrinsics.camera_matrix, lens.opencv_dist(intrinsics)).reshape(-1, 2)
    brown, target = LensMisfit(), lens.distort(xy, intrinsics)
    fit = least_squares(lambda p: (brown.distort(xy, intrinsics.with_vector(p)) - target).ravel(), intrinsics.vector(),
                        x_scale="jac")
    n = np.linalg.norm(fit.fun.reshape(-1, 2), axis=1)
    return float(np.sqrt(np.mean(n**2))), float(n.max())


def printed_rng(seed: int) -> np.random.Generator:
    """The draws of the prints: their own stream of the session's seed (the stage's and camera's are untouched)."""
    return np.random.default_rng([int(seed), 35])
