"""A true lens the 5-coefficient model cannot follow: the simulator's lens-misfit realism switch (issue 35).

Real lenses leave 0.03-0.3 px of misfit to OpenCV's 5-coefficient model across
the image (SPEC 15). The simulator gets one by adding rational (k4-k6) and
thin-prism (s1-s4) terms of a fixed shape to the rig's lens, scaled so that
the best 5-coefficient refit of the whole image leaves ``misfit_px`` RMS: that
is the part no calibration with the session's model can take out.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.truth.simulation_spec import SimulationSpec

# the shape of the added terms (k4, k5, k6, s1, s2, s3, s4): a rational radial part and a thin prism of the size a
# decentred element leaves; only their scale is set by the misfit asked for
MISFIT_SHAPE = np.array([0.3, -0.2, 0.1, 2e-3, -1e-3, -1.5e-3, 8e-4])


def _grid_rays(intr: CameraIntrinsics, n: tuple[int, int] = (32, 24)) -> np.ndarray:
    """Camera-frame rays (M, 3) through a grid over the image (through the 5-coefficient lens: the field seen)."""
    from lps_gui.core.intrinsics.crossval import pixel_grid, unproject

    rays = unproject(pixel_grid(intr.image_size, n).reshape(-1, 2), intr)
    return rays[np.all(np.isfinite(rays), axis=1)]


def refit_residual_px(true: CameraIntrinsics, rays: np.ndarray | None = None, iterations: int = 5) -> float:
    """RMS px over the image of ``true`` minus the best 5-coefficient lens (the 9 intrinsics refitted)."""
    five = replace(true, higher=np.zeros(7), covariance=None)
    rays = _grid_rays(five) if rays is None else rays
    target = project(rays, true).uv
    for _ in range(iterations):  # Gauss-Newton on the 9 intrinsics: the residual is nearly linear in them
        p = project(rays, five, want_intrinsics_jacobian=True)
        J = p.d_uv_d_intrinsics.reshape(-1, 9)
        step = np.linalg.lstsq(J, (target - p.uv).ravel(), rcond=None)[0]
        five = five.with_vector(five.vector() + step)
    return float(np.sqrt(np.mean(np.sum((target - project(rays, five).uv) ** 2, axis=1))))


def misfit_lens(intr: CameraIntrinsics, misfit_px: float) -> CameraIntrinsics:
    """``intr`` with rational and thin-prism terms that a 5-coefficient refit leaves ``misfit_px`` RMS of."""
    if misfit_px <= 0:
        return replace(intr, higher=np.zeros(7))
    rays = _grid_rays(replace(intr, higher=np.zeros(7)))
    unit = refit_residual_px(replace(intr, higher=MISFIT_SHAPE * 1e-3), rays)
    scale = 1e-3 * misfit_px / unit
    for _ in range(3):  # the residual is not quite linear in the scale: a few secant steps
        got = refit_residual_px(replace(intr, higher=MISFIT_SHAPE * scale), rays)
        scale *= misfit_px / got
    return replace(intr, higher=MISFIT_SHAPE * scale)


def with_lens_misfit(spec: SimulationSpec, misfit_px: float) -> SimulationSpec:
    """``spec`` whose true camera has a lens the 5-coefficient model misses by ``misfit_px`` RMS over the image."""
    if misfit_px <= 0:
        return spec
    return replace(spec, rig=replace(spec.rig, intrinsics=misfit_lens(spec.rig.intrinsics, misfit_px)),
                   name=f"{spec.name}, lens misfit {misfit_px:g} px")
