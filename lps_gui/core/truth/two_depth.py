"""Two-depth constellations on a stage with angular error motions (SPEC 14): the rig the simulator renders.

The paper's camera 800 mm from a row of 10x7 ChArUco targets of 30 mm squares
and, 300 mm nearer, a row of 10x7 targets of 15 mm squares (smaller, so that
both rows fit the view); the stage rolls, pitches and yaws along smooth curves
of 50-160 urad plus a few urad per stop (:class:`StageErrorModel`). One
:class:`Rig` whose board is target 0 (the world frame) carries the camera, so
the truth of every stop's angles is the rig's (:meth:`Rig.camera_poses`), and
:func:`lps_gui.core.geometry.target_rig.observe` or the targets renderer see the layout
from those poses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout, observe, two_depth_layout
from lps_gui.core.geometry.targets import pack_targets
from lps_gui.core.models.lps_model import unit
from lps_gui.core.models.target_model import TargetObservations
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulation_spec import SimulationSpec
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel

PAPER_CAMERA = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 960.0, 540.0)  # 8 mm lens, 3.45 um pixels
FAR_BOARD = Board(10, 7, 30.0, type="charuco", marker_mm=22.0)
NEAR_BOARD = Board(10, 7, 15.0, type="charuco", marker_mm=11.0)
EDGE_PX = 12.0  # corners kept this far inside the image
MOUNT_RVEC = (0.01, -0.02, 0.005)  # the camera's mounting on the carriage, rad (a real rig is never square)


def angular_stage_errors(travel_mm: float, angle_noise_urad: float = 3.0) -> StageErrorModel:
    """A stage that rolls, pitches and yaws along smooth curves of 50-160 urad over ``travel_mm``.

    Roll 60 sin(2 pi x / L), pitch 80 (x / L)^2 + 15 sin(2 pi x / 400 mm),
    yaw 60 cos(pi x / L) (urad; peak-to-valley 120, about 100 and 120), plus
    ``angle_noise_urad`` per stop; the
    carriage bows 10 um across and 15 um along the view; 20 ppm of scale and a
    4 um lead-screw periodic error.
    """
    L, Lm = float(travel_mm), float(travel_mm) / 1000.0
    bow = (ErrorProfile(amplitude=10.0, period_mm=2 * L), ErrorProfile(amplitude=15.0, period_mm=2 * L))
    return StageErrorModel(
        scale_ppm=20.0, periodic_um=4.0, pitch_mm=5.0, repeatability_um=0.5, straightness_um=bow,
        roll_urad=ErrorProfile(amplitude=60.0, period_mm=L),
        pitch_urad=ErrorProfile(poly=(0.0, 0.0, 80.0 / Lm**2), amplitude=15.0, period_mm=400.0),
        yaw_urad=ErrorProfile(amplitude=60.0, period_mm=2 * L, phase_rad=math.pi / 2),
        angle_noise_urad=angle_noise_urad)


@dataclass(frozen=True)
class TwoDepthRig:
    """A camera on a stage of one axis in front of a two-depth constellation; world = target 0's frame."""

    rig: Rig  # rig.board is target 0's board; rig.errors the stage's
    layout: TargetLayout


def two_depth_rig(travel_mm: float = 1524.0, distance_mm: float = 800.0, near_mm: float = 300.0,
                  far: Board = FAR_BOARD, near: Board = NEAR_BOARD, intrinsics: CameraIntrinsics = PAPER_CAMERA,
                  errors: StageErrorModel | None = None, mount_error_sigma: tuple[float, float] = (0.01, 2.0),
                  seed: int = 0) -> TwoDepthRig:
    """The paper's two-depth case: a far row at ``distance_mm`` and a near row ``near_mm`` nearer (0: one plane).

    Far targets at a pitch of their width plus a gap of 3 % (at least 10 mm:
    340 mm for 30 mm squares), as many as cover the travel and the view at its
    ends; the near row beside it in the image at the same rule's pitch, over
    the same span; the camera centre 44 mm above the far row's first corner
    row, so each row fills about half the image height. ``near_mm=0`` moves
    the near row into the far plane, 150 mm beside the far row.
    ``mount_error_sigma``: (rad, mm) of every target's mounting but target 0's.
    """
    view_w = intrinsics.image_size[0] / intrinsics.fx * distance_mm
    far_w, near_w = (far.cols + 1) * far.square_mm, (near.cols + 1) * near.square_mm
    far_pitch = far_w + max(10.0, 0.03 * far_w)  # gaps as a row's (core/planning/rows)
    n_far = max(2, math.ceil((travel_mm + 0.5 * view_w - far_w) / far_pitch) + 1)
    span = (n_far - 1) * far_pitch + (far.cols - 1) * far.square_mm  # first to last inner corner
    near_pitch = near_w + max(10.0, 0.03 * near_w)
    n_near = max(2, math.ceil((span - (near.cols - 1) * near.square_mm) / near_pitch) + 1)
    near_span = (n_near - 1) * near_pitch + (near.cols - 1) * near.square_mm
    # the far row fills the lower half of the image, the near row the upper half (image y grows with world y)
    reach = (0.5 * intrinsics.image_size[1] - EDGE_PX) / intrinsics.fy  # tan of the usable half view height
    far_h = (far.rows - 1) * far.square_mm
    camera_y = far_h - reach * distance_mm
    near_y = camera_y - reach * (distance_mm - near_mm)  # the near row's first corner row at the top edge
    targets = pack_targets([far] * n_far + [near] * n_near,
                           [f"F{j}" for j in range(n_far)] + [f"N{j}" for j in range(n_near)])
    layout = two_depth_layout(targets[:n_far], targets[n_far:], far_pitch, near_pitch, max(near_mm, 0.0),
                              (0.5 * (span - near_span), near_y), *mount_error_sigma, seed=seed)
    R = exp_so3(np.array(MOUNT_RVEC))
    C0 = np.array([0.5 * (span - travel_mm), camera_y, -float(distance_mm)])
    rig = Rig(far, intrinsics, R, C0, unit(np.array([1.0, 0.002, -0.001])),
              errors if errors is not None else angular_stage_errors(travel_mm))
    return TwoDepthRig(rig, layout)


@dataclass
class TwoDepthViews:
    """Corners of every stop and the truth behind them."""

    observations: TargetObservations
    rotations_world: np.ndarray  # (K, 3) rad: the carriage's rotation vectors in the world frame (the truth)
    centres_world: np.ndarray  # (K, 3) mm: true camera centres
    axis_mm: np.ndarray  # (K,) true position along the axis


def observe_stops(tr: TwoDepthRig, targets_mm: np.ndarray, noise_px: float = 0.1, seed: int = 0) -> TwoDepthViews:
    """The corners of ``tr``'s targets from the true poses at commanded ``targets_mm`` (approached moving +)."""
    x = np.asarray(targets_mm, dtype=float)
    pose = tr.rig.errors.true_pose(x, np.ones_like(x), np.random.default_rng(seed))
    R, t = tr.rig.camera_poses(pose)
    uv = observe(tr.layout, tr.rig.intrinsics, R, t, noise_px=noise_px, seed=seed + 1)
    obs = TargetObservations(list(tr.layout.targets), uv, x[:, None], [f"stop{i:04d}.png" for i in range(len(x))])
    C = -np.einsum("kji,kj->ki", R, t)
    return TwoDepthViews(obs, tr.rig.carriage_rotations(pose), C, pose.axis_mm)


def two_depth_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None,
                   plan: Any = None, near_mm: float = 300.0, name: str = "paper-two-depth") -> SimulationSpec:
    """A simulation of :func:`two_depth_rig` (SPEC 14's case): the paper's 1524 mm X axis in 241 stops of 6.35 mm.

    ``near_mm=0``: both rows in one plane (preset ``paper-one-plane``: the tilts are not resolved).
    """
    plan = plan or Plan(start_mm=0.0, stop_mm=1524.0, step_mm=6.35)
    t = plan.targets()
    travel = float(t[-1] - t[0])
    tr = two_depth_rig(travel, near_mm=near_mm, errors=errors, seed=seed)
    rig = replace(tr.rig, C0_board=tr.rig.C0_board - float(t[0]) * tr.rig.u_board)  # commanded t[0] at the start
    return SimulationSpec(name, rig, plan, noise_px=noise_px, seed=seed, layout=tr.layout)


def one_plane_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None, plan: Any = None) -> Any:
    """:func:`two_depth_spec` with both rows in one plane: what one depth resolves of the tilts (SPEC 11)."""
    return two_depth_spec(seed, noise_px, errors, plan, near_mm=0.0, name="paper-one-plane")


TWO_DEPTH_PRESETS = {"paper-two-depth": two_depth_spec, "paper-one-plane": one_plane_spec}
