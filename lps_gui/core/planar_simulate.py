"""Synthetic planar (XY) sessions with known truth, at the level of corners.

The planar counterpart of :mod:`lps_gui.core.simulate`: a
:class:`PlanarSimulationSpec` describes rig, plan, noise and injected outlier
views; :func:`simulate_planar_views` projects the board through every true
pose. The truth it returns holds the carriage's true stage-plane positions
and the board-plane positions (what a constant-orientation model measures
when the carriage tilts: the Abbe convention of the 1-D case).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lps_gui.core.board import Board
from lps_gui.core.camera_model import project_board
from lps_gui.core.planar_model import PlanarState, planar_positions_only
from lps_gui.core.planar_plan import PlanarPlan, PlanarStop
from lps_gui.core.planar_rig import PlanarErrorModel, PlanarRig, PlanarTruePose
from lps_gui.core.rotation import exp_so3
from lps_gui.core.simulate import PAPER_INTRINSICS
from lps_gui.core.stage_errors import ErrorProfile, StageErrorModel
from lps_gui.errors import InputError


@dataclass(frozen=True)
class PlanarSimulationSpec:
    """A simulated planar experiment; every random draw comes from ``seed``."""

    name: str
    rig: PlanarRig
    plan: PlanarPlan
    noise_px: float = 0.1
    missing_fraction: float = 0.0
    replaced_views: tuple[int, ...] = ()
    replaced_offset: int = 37
    bumped_views: tuple[int, ...] = ()
    bump_mrad: float = 3.0
    seed: int = 0


@dataclass
class PlanarSimulatedViews:
    stops: list[PlanarStop]
    corners_px: np.ndarray  # shape (K, N, 2), NaN where missing
    R_cam_board: np.ndarray  # shape (K, 3, 3)
    t_cam_board: np.ndarray  # shape (K, 3)
    pose: PlanarTruePose
    board_plane_mm: np.ndarray  # shape (K, 2): true positions as the constant-orientation model sees them
    truth: dict[str, Any] = field(default_factory=dict)


def nominal_planar_state(rig: PlanarRig, xy_mm: np.ndarray) -> PlanarState:
    """The planar model of an error-free rig, positions ``xy_mm`` (K, 2) in the stage plane."""
    R = rig.R_cam_board
    l0 = -R @ rig.C0_board
    P = R @ (-rig.axes_board)  # n_x = -R e_x, n_y = -R e_y; third column completes a rotation
    P[:, 2] = np.cross(P[:, 0], P[:, 1])
    return PlanarState(R.copy(), l0, P, np.asarray(xy_mm, dtype=float).copy(), rig.intrinsics)


def simulate_planar_views(spec: PlanarSimulationSpec) -> PlanarSimulatedViews:
    """Project the board through every true pose, add noise, drop and swap views."""
    rng = np.random.default_rng(spec.seed)
    stops = list(spec.plan.stops())
    if not stops:
        raise InputError("planar simulation: the plan has no targets")
    target = np.array([s.target_mm for s in stops])
    approach = np.array([s.approach for s in stops], dtype=float)
    pose = spec.rig.errors.true_pose(target, approach, rng)
    R, t = spec.rig.camera_poses(pose)
    K = len(stops)
    for i in spec.bumped_views:
        if not 0 <= i < K:
            raise InputError(f"planar simulation: bumped view {i} is outside 0..{K - 1}")
        axis = rng.normal(size=3)
        axis[2] = abs(axis[2]) + 1.0
        R[i] = exp_so3(axis / np.linalg.norm(axis) * spec.bump_mrad * 1e-3) @ R[i]
    X = spec.rig.board.object_points()
    uv = project_board(R, t, X, spec.rig.intrinsics)
    board_plane = planar_positions_only(nominal_planar_state(spec.rig, pose.plane_mm), X, uv,
                                        np.ones(uv.shape[:2], bool))
    corners = uv + rng.normal(0.0, spec.noise_px, size=uv.shape)
    for i in spec.replaced_views:
        if not 0 <= i < K:
            raise InputError(f"planar simulation: replaced view {i} is outside 0..{K - 1}")
        j = (i + spec.replaced_offset) % K
        corners[i] = uv[j] + rng.normal(0.0, spec.noise_px, size=uv[j].shape)
    w, h = spec.rig.intrinsics.image_size
    outside = (corners[..., 0] < 0) | (corners[..., 0] > w - 1) | (corners[..., 1] < 0) | (corners[..., 1] > h - 1)
    corners[outside | (rng.random(corners.shape[:2]) < spec.missing_fraction)] = np.nan
    truth = {
        "axes": ["X", "Y"],
        "plane_mm": pose.plane_mm.tolist(),
        "board_plane_mm": board_plane.tolist(),
        "normal_um": pose.normal_um.tolist(),
        "angles_urad": pose.angles_urad.tolist(),
        "replaced_views": list(spec.replaced_views),
        "bumped_views": list(spec.bumped_views),
        "rig": spec.rig.to_dict(),
        "noise_px": spec.noise_px,
        "seed": spec.seed,
    }
    return PlanarSimulatedViews(stops, corners, R, t, pose, board_plane, truth)


def paper_planar_errors(squareness_urad: float = 150.0, scale_x_ppm: float = 80.0,
                        scale_y_ppm: float = -50.0) -> PlanarErrorModel:
    """The paper's XY gantry as we assume it: lead screws with periodic error, out of square."""
    x = StageErrorModel(scale_ppm=scale_x_ppm, periodic_um=3.0, pitch_mm=5.0, backlash_um=5.0, repeatability_um=0.5,
                        straightness_um=(ErrorProfile(poly=(0.0, 0.0, -60.0)), ErrorProfile(poly=(0.0, 10.0))))
    y = StageErrorModel(scale_ppm=scale_y_ppm, periodic_um=2.0, pitch_mm=4.0, periodic_phase_rad=1.0, backlash_um=4.0,
                        repeatability_um=0.5,
                        straightness_um=(ErrorProfile(amplitude=2.0, period_mm=70.0), ErrorProfile()))
    return PlanarErrorModel(x=x, y=y, squareness_urad=squareness_urad)


def paper_planar_spec(seed: int = 0, noise_px: float = 0.1, errors: PlanarErrorModel | None = None,
                      plan: PlanarPlan | None = None, distance_mm: float = 600.0) -> PlanarSimulationSpec:
    """The paper's camera and board on an XY gantry: a 15 x 9 grid at 10 mm, 600 mm from the board."""
    board = Board(cols=30, rows=18, square_mm=10.0)
    plan = plan or PlanarPlan(start_mm=(0.0, 0.0), stop_mm=(140.0, 80.0), step_mm=(10.0, 10.0))
    t = plan.targets()
    centre = (0.5 * (t[:, 0].min() + t[:, 0].max()), 0.5 * (t[:, 1].min() + t[:, 1].max()))
    rig = PlanarRig.facing_board(board, PAPER_INTRINSICS, distance_mm, centre,
                                 errors=errors if errors is not None else paper_planar_errors())
    return PlanarSimulationSpec("paper-planar", rig, plan, noise_px=noise_px, seed=seed)


def small_planar_spec(seed: int = 0, noise_px: float = 0.2, errors: PlanarErrorModel | None = None,
                      plan: PlanarPlan | None = None) -> PlanarSimulationSpec:
    """A small, fast planar case for tests: 640x480, 9x6 board, a 6 x 4 grid."""
    from lps_gui.core.simulate import small_spec

    one_d = small_spec()
    plan = plan or PlanarPlan(start_mm=(0.0, 0.0), stop_mm=(50.0, 30.0), step_mm=(10.0, 10.0))
    t = plan.targets()
    centre = (0.5 * (t[:, 0].min() + t[:, 0].max()), 0.5 * (t[:, 1].min() + t[:, 1].max()))
    rig = PlanarRig.facing_board(one_d.rig.board, one_d.rig.intrinsics, 500.0, centre,
                                 errors=errors if errors is not None else paper_planar_errors())
    return PlanarSimulationSpec("small-planar", rig, plan, noise_px=noise_px, seed=seed)


PLANAR_PRESETS = {"paper-planar": paper_planar_spec, "small-planar": small_planar_spec}


def planar_preset(name: str, **overrides: Any) -> PlanarSimulationSpec:
    if name not in PLANAR_PRESETS:
        raise InputError(f"planar simulation: unknown preset {name!r}; choose one of {', '.join(PLANAR_PRESETS)}")
    spec = PLANAR_PRESETS[name]()
    return replace(spec, **overrides) if overrides else spec
