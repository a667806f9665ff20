"""Synthetic LPS sessions with known truth (point level), and the rig presets, on one axis or two.

A :class:`SimulationSpec` is the whole description of a simulated experiment:
rig (a :class:`Rig` on one axis, a :class:`Rig` on an XY gantry), plan,
corner noise, missing corners and injected outlier views. The image
simulator renders the same spec; here we only project the corners. On a
gantry the truth also holds the board-plane positions (what a
constant-orientation model measures when the carriage tilts: the Abbe
convention of the 1-D case).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout, observe
from lps_gui.core.models.planar_model import PlanarState, planar_positions_only
from lps_gui.core.planning.plan import Plan, PlannedStop
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulation_spec import SimulationSpec
from lps_gui.core.truth.stage_errors import (
    ErrorProfile,
    PlanarErrorModel,
    PlanarTruePose,
    StageErrorModel,
    TruePose,
)
from lps_gui.errors import InputError


def layout_truth(layout: TargetLayout) -> list[dict[str, Any]]:
    """session.json ``truth.targets``: every target's true pose in the world (target 0's) frame."""
    from lps_gui.core.geometry.rotation import log_so3

    return [{"id": t.id, "rvec_rad": log_so3(layout.Q[j]).tolist(), "p_mm": layout.p[j].tolist()}
            for j, t in enumerate(layout.targets)]


def placement_poses(spec: SimulationSpec, stops: list[PlannedStop], R: np.ndarray, t: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The camera's pose on the board each view sees: a stitched session's board where it was placed for the view's
    segment (X_w = Q_k X + p_k, so X_c = R Q_k X + R p_k + t); any other session's poses as they are."""
    if not spec.stitched:
        return R, t
    seg = np.array([s.segment for s in stops], int)
    return R @ spec.layout.Q[seg], np.einsum("kij,kj->ki", R, spec.layout.p[seg]) + t


def project_scene(spec: SimulationSpec, R: np.ndarray, t: np.ndarray, stops: list[PlannedStop] | None = None
                  ) -> np.ndarray:
    """Noise-free corners (K, N, 2) of the board, or of every target laid end to end (NaN where a target's
    corner is outside the image or behind another target); a stitched session's (``stops`` given) board where
    it lay during each view's segment."""
    if spec.stitched and stops is not None:
        R, t = placement_poses(spec, stops, R, t)
    if spec.one_board:
        return project_board(R, t, spec.rig.board.object_points(), spec.rig.intrinsics)
    return observe(spec.layout, spec.rig.intrinsics, R, t, border_px=0.0)


@dataclass
class SimulatedViews:
    """What a point simulation produces."""

    stops: list[PlannedStop]
    corners_px: np.ndarray  # shape (K, N, 2), NaN where missing
    R_cam_board: np.ndarray  # shape (K, 3, 3): true poses
    t_cam_board: np.ndarray  # shape (K, 3)
    truth: dict[str, Any] = field(default_factory=dict)
    pose: PlanarTruePose | None = None  # a gantry's true poses
    board_plane_mm: np.ndarray | None = None  # gantry, (K, 2): true positions as the constant-orientation model sees them


def nominal_planar_state(rig: Rig, xy_mm: np.ndarray) -> PlanarState:
    """The planar model of an error-free rig, positions ``xy_mm`` (K, 2) in the stage plane."""
    R = rig.R_cam_board
    l0 = -R @ rig.C0_board
    P = R @ (-rig.axes_board)  # n_x = -R e_x, n_y = -R e_y; third column completes a rotation
    P[:, 2] = np.cross(P[:, 0], P[:, 1])
    return PlanarState(R.copy(), l0, P, np.asarray(xy_mm, dtype=float).copy(), rig.intrinsics)


def bump_views(R: np.ndarray, views: tuple[int, ...], bump_mrad: float, rng: np.random.Generator, what: str) -> None:
    """Knock the camera at ``views`` (in place): a rotation by ``bump_mrad``, mostly about the optical axis
    (not absorbable by a shift)."""
    K = len(R)
    for i in views:
        if not 0 <= i < K:
            raise InputError(f"{what}: bumped view {i} is outside 0..{K - 1}")
        axis = rng.normal(size=3)
        axis[2] = abs(axis[2]) + 1.0
        axis /= np.linalg.norm(axis)
        R[i] = exp_so3(axis * bump_mrad * 1e-3) @ R[i]


def true_views(spec: SimulationSpec, rng: np.random.Generator) -> tuple[list[PlannedStop], np.ndarray, np.ndarray, dict]:
    """True camera poses of every planned frame, and the truth record.

    The carriage's true pose depends on the approach direction (backlash) and
    draws repeatability noise once per stop (the frames of a stop share it).
    A command inside the stage's dead band leaves the carriage where the last
    stop left it (:meth:`StageErrorModel.reached_mm`); with ``spec.vibration``
    frame f of a stop sees the ringing at ``settle_s + f * frame_interval_s``
    after the move (the frame's pose at the start of its exposure).
    """
    stops = list(spec.plan.stops())
    if not stops:
        raise InputError("simulation: the plan has no targets")
    target = np.array([s.target_mm for s in stops])
    direction = np.array([1.0 if s.direction == "+" else -1.0 for s in stops])
    first = np.flatnonzero(np.array([s.frame == 0 for s in stops]))  # one move per stop
    stop_of = np.cumsum([s.frame == 0 for s in stops]) - 1  # shape (K,): each frame's stop
    errors = spec.rig.errors
    reached, moved = errors.reached_mm(target[first])
    at_stop = errors.true_pose(reached, direction[first], rng)
    last_move = np.maximum.accumulate(np.where(moved, np.arange(first.size), 0))  # a stuck stop keeps the last pose
    pick = last_move[stop_of]
    pose = TruePose(at_stop.axis_mm[pick], at_stop.straightness_um[pick], at_stop.angles_urad[pick])
    if spec.vibration is not None:
        since_s = spec.plan.settle_s + spec.frame_interval_s * np.array([s.frame for s in stops], dtype=float)
        ring_um = np.where(moved[stop_of], spec.vibration.offset_um(since_s, direction[first][pick]), 0.0)
        pose = replace(pose, axis_mm=pose.axis_mm + 1e-3 * ring_um)
    R, t = spec.rig.camera_poses(pose)
    bump_views(R, spec.bumped_views, spec.bump_mrad, rng, "simulation")
    s_true = pose.axis_mm - pose.axis_mm[0]
    truth = {
        "positions_mm": s_true.tolist(),
        "axis_mm": pose.axis_mm.tolist(),
        "straightness_um": pose.straightness_um.tolist(),
        "angles_urad": pose.angles_urad.tolist(),
        "replaced_views": list(spec.replaced_views),
        "bumped_views": list(spec.bumped_views),
        "R_cam_board": spec.rig.R_cam_board.tolist(),
        "C0_board": spec.rig.C0_board.tolist(),
        "u_board": spec.rig.u_board.tolist(),
        "stage_errors": spec.rig.errors.to_dict(),
        "board": {"type": spec.rig.board.type, "inner_corners": [spec.rig.board.cols, spec.rig.board.rows],
                  "square_mm": spec.rig.board.square_mm},
        "intrinsics": {"image_size": list(spec.rig.intrinsics.image_size),
                       "camera_matrix": spec.rig.intrinsics.camera_matrix.tolist(), "dist": spec.rig.intrinsics.cv_dist.tolist()},
        "noise_px": spec.noise_px,
        "seed": spec.seed,
    }
    truth.update(spec.realism_truth())
    if spec.vibration is not None:
        truth["vibration"] = {**spec.vibration.to_dict(), "frame_interval_s": spec.frame_interval_s}
    if spec.layout is not None:
        truth["targets"] = layout_truth(spec.layout)
    return stops, R, t, truth


def frame_since_move_s(spec: SimulationSpec, frame: int) -> float | None:
    """captures.jsonl ``since_move_s`` of a simulated frame of a ringing stage (the engine's convention: after the
    settle wait and the frame's exposure); None without ringing."""
    if spec.vibration is None:
        return None
    return round(spec.plan.settle_s + spec.frame_interval_s * (frame + 1), 6)


def planar_true_views(spec: SimulationSpec, rng: np.random.Generator
                      ) -> tuple[list[PlannedStop], np.ndarray, np.ndarray, PlanarTruePose]:
    """A gantry's :func:`true_views`: per-axis approach sides (backlash), repeatability once per stop."""
    stops = list(spec.plan.stops())
    if not stops:
        raise InputError("planar simulation: the plan has no targets")
    target = np.array([s.target_mm for s in stops])
    approach = np.array([s.approach for s in stops], dtype=float)
    pose = spec.rig.errors.true_pose(target, approach, rng)
    R, t = spec.rig.camera_poses(pose)
    bump_views(R, spec.bumped_views, spec.bump_mrad, rng, "planar simulation")
    return stops, R, t, pose


def simulate_views(spec: SimulationSpec) -> SimulatedViews:
    """Project the board through every true pose, add noise, drop and swap views (one or two axes)."""
    rng = np.random.default_rng(spec.seed)
    pose = board_plane = None
    if spec.plan.planar:
        stops, R, t, pose = planar_true_views(spec, rng)
    else:
        stops, R, t, truth = true_views(spec, rng)
    X = spec.rig.board.object_points()
    uv = project_scene(spec, R, t, stops)  # shape (K, N, 2)
    if pose is not None and spec.layout is not None:  # a constellation: no one board's plane; the stage plane
        truth = {**planar_truth(spec, pose, pose.plane_mm), "targets": layout_truth(spec.layout)}
    elif pose is not None:
        board_plane = planar_positions_only(nominal_planar_state(spec.rig, pose.plane_mm), X, uv,
                                            np.ones(uv.shape[:2], bool))
        truth = planar_truth(spec, pose, board_plane)
    noise = rng.normal(0.0, spec.noise_px, size=uv.shape)
    if spec.noise_clip_px is not None:
        noise = np.clip(noise, -spec.noise_clip_px, spec.noise_clip_px)
    corners = uv + noise
    K = len(stops)
    what = "planar simulation" if spec.plan.planar else "simulation"
    for i in spec.replaced_views:
        if not 0 <= i < K:
            raise InputError(f"{what}: replaced view {i} is outside 0..{K - 1}")
        j = (i + spec.replaced_offset) % K
        corners[i] = uv[j] + rng.normal(0.0, spec.noise_px, size=uv[j].shape)
    w, h = spec.rig.intrinsics.image_size
    outside = (corners[..., 0] < 0) | (corners[..., 0] > w - 1) | (corners[..., 1] < 0) | (corners[..., 1] > h - 1)
    missing = outside | (rng.random(corners.shape[:2]) < spec.missing_fraction)
    corners[missing] = np.nan
    return SimulatedViews(stops, corners, R, t, truth, pose, board_plane)


def planar_truth(spec: SimulationSpec, pose: PlanarTruePose, board_plane_mm: np.ndarray) -> dict[str, Any]:
    """The truth record of a simulated gantry session (session.json ``truth``, SPEC 10)."""
    return {
        "axes": ["X", "Y"],
        "plane_mm": pose.plane_mm.tolist(),
        "board_plane_mm": board_plane_mm.tolist(),
        "normal_um": pose.normal_um.tolist(),
        "angles_urad": pose.angles_urad.tolist(),
        "replaced_views": list(spec.replaced_views),
        "bumped_views": list(spec.bumped_views),
        "rig": spec.rig.to_dict(),
        "noise_px": spec.noise_px,
        "seed": spec.seed,
    }


# ----------------------------------------------------------------------------- presets

PAPER_INTRINSICS = CameraIntrinsics.from_values(
    (1920, 1080),
    fx=1396.0,  # 8.18 mm lens on 5.86 um pixels
    fy=1396.0,
    cx=951.59,
    cy=551.08,
    dist=(-0.169, 0.111, -0.0007, -0.00002, -0.02),
)


def paper_stage_errors() -> StageErrorModel:
    """A realistic lead-screw stage, inside the paper's +-20 um accuracy spec."""
    return StageErrorModel(
        scale_ppm=25.0,
        periodic_um=4.0,
        pitch_mm=5.0,
        backlash_um=6.0,
        repeatability_um=1.0,
        straightness_um=(ErrorProfile(poly=(0.0, 0.0, -40.0), amplitude=2.0, period_mm=97.0),
                         ErrorProfile(poly=(0.0, 8.0), amplitude=1.5, period_mm=61.0)),
        roll_urad=ErrorProfile(amplitude=15.0, period_mm=150.0),
        pitch_urad=ErrorProfile(poly=(0.0, 30.0)),
        yaw_urad=ErrorProfile(amplitude=10.0, period_mm=200.0, phase_rad=0.5),
    )


def paper_rig_spec(
    seed: int = 0,
    noise_px: float = 0.1,
    errors: StageErrorModel | None = None,
    plan: Plan | None = None,
    distance_mm: float = 600.0,
    name: str = "paper-rig",
) -> SimulationSpec:
    """The paper's rig: 1920x1080, 18x30 board, 400 stops 1 mm apart, 600 mm away."""
    board = Board(cols=30, rows=18, square_mm=10.0)
    plan = plan or Plan(start_mm=0.0, stop_mm=399.0, step_mm=1.0, directions="+", runs=1)
    t = plan.targets()
    rig = Rig.facing_board(board, PAPER_INTRINSICS, distance_mm, (t[0], t[-1]), errors=errors)
    return SimulationSpec(name, rig, plan, noise_px=noise_px, seed=seed)


CLOSEUP_DISTANCE_MM = 450.0  # the board fills the view: ~1.4 um per view, what micrometre steps need


def paper_closeup_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None,
                       plan: Plan | None = None) -> SimulationSpec:
    """The paper's camera and board 450 mm apart over 200 mm of travel: the set-up of the ASME B5.64
    incremental-step and settling tests (a small stage, repeatability 0.1 um)."""
    errors = errors if errors is not None else replace(paper_stage_errors(), repeatability_um=0.1)
    plan = plan or Plan(start_mm=0.0, stop_mm=200.0, step_mm=10.0, directions="both", runs=1)
    return paper_rig_spec(seed, noise_px, errors, plan, CLOSEUP_DISTANCE_MM, "paper-closeup")


def paper_synthetic_spec(seed: int = 0) -> SimulationSpec:
    """The paper's synthetic case: sine-wave step variation, |noise| < 1 px, no distortion."""
    board = Board(cols=8, rows=4, square_mm=30.0)
    intr = CameraIntrinsics.from_values((1920, 1080), 1396.0, 1396.0, 960.0, 540.0)
    plan = Plan(start_mm=0.0, stop_mm=99.0, step_mm=1.0)
    errors = StageErrorModel(periodic_um=50.0, pitch_mm=25.0)
    rig = Rig.facing_board(board, intr, 600.0, (0.0, 99.0), errors=errors)
    return SimulationSpec("paper-synthetic", rig, plan, noise_px=0.4, noise_clip_px=1.0, seed=seed)


def small_spec(
    seed: int = 0,
    views: int = 30,
    noise_px: float = 0.2,
    directions: str = "+",
    runs: int = 1,
    errors: StageErrorModel | None = None,
) -> SimulationSpec:
    """A small, fast case for tests: 640x480, 9x6 board, 30 stops."""
    board = Board(cols=9, rows=6, square_mm=20.0)
    intr = CameraIntrinsics.from_values((640, 480), 600.0, 600.0, 322.0, 238.0, dist=(-0.12, 0.08, 0.0005, -0.0003, -0.01))
    plan = Plan(start_mm=0.0, stop_mm=float(views - 1) * 2.0, step_mm=2.0, directions=directions, runs=runs)
    errors = errors if errors is not None else StageErrorModel(periodic_um=5.0, pitch_mm=8.0, scale_ppm=100.0, backlash_um=4.0, repeatability_um=1.0)
    t = plan.targets()
    rig = Rig.facing_board(board, intr, 500.0, (t[0], t[-1]), errors=errors)
    return SimulationSpec("small", rig, plan, noise_px=noise_px, seed=seed)


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
                      plan: Plan | None = None, distance_mm: float = 600.0) -> SimulationSpec:
    """The paper's camera and board on an XY gantry: a 15 x 9 grid at 10 mm, 600 mm from the board."""
    board = Board(cols=30, rows=18, square_mm=10.0)
    plan = plan or Plan.xy(start_mm=(0.0, 0.0), stop_mm=(140.0, 80.0), step_mm=(10.0, 10.0))
    t = plan.targets()
    centre = (0.5 * (t[:, 0].min() + t[:, 0].max()), 0.5 * (t[:, 1].min() + t[:, 1].max()))
    rig = Rig.facing_board(board, PAPER_INTRINSICS, distance_mm, centre,
                                 errors=errors if errors is not None else paper_planar_errors())
    return SimulationSpec("paper-planar", rig, plan, noise_px=noise_px, seed=seed)


def small_planar_spec(seed: int = 0, noise_px: float = 0.2, errors: PlanarErrorModel | None = None,
                      plan: Plan | None = None) -> SimulationSpec:
    """A small, fast planar case for tests: 640x480, 9x6 board, a 6 x 4 grid."""
    one_d = small_spec()
    plan = plan or Plan.xy(start_mm=(0.0, 0.0), stop_mm=(50.0, 30.0), step_mm=(10.0, 10.0))
    t = plan.targets()
    centre = (0.5 * (t[:, 0].min() + t[:, 0].max()), 0.5 * (t[:, 1].min() + t[:, 1].max()))
    rig = Rig.facing_board(one_d.rig.board, one_d.rig.intrinsics, 500.0, centre,
                                 errors=errors if errors is not None else paper_planar_errors())
    return SimulationSpec("small-planar", rig, plan, noise_px=noise_px, seed=seed)


PRESETS = {
    "paper-rig": paper_rig_spec,
    "paper-synthetic": paper_synthetic_spec,
    "small": small_spec,
    "paper-closeup": paper_closeup_spec,
}
PLANAR_PRESETS = {"paper-planar": paper_planar_spec, "small-planar": small_planar_spec}


from lps_gui.core.planning.target_presets import PLANAR_TARGET_PRESETS, TARGET_PRESETS  # noqa: E402 (rows of targets; they import core/truth/simulation_spec, not this module)
from lps_gui.core.truth.two_depth import TWO_DEPTH_PRESETS  # noqa: E402 (SPEC 14: targets at two depths; imports core/truth/simulation_spec too)

PRESETS.update(TARGET_PRESETS)
PRESETS.update(TWO_DEPTH_PRESETS)
PLANAR_PRESETS.update(PLANAR_TARGET_PRESETS)


def preset(name: str, planar: bool = False, **overrides: Any) -> SimulationSpec:
    """A named preset (of an XY gantry when ``planar``); keyword overrides replace fields of the spec."""
    table, what = (PLANAR_PRESETS, "planar simulation") if planar else (PRESETS, "simulation")
    if name not in table:
        raise InputError(f"{what}: unknown preset {name!r}; choose one of {', '.join(table)}")
    spec = table[name]()
    return replace(spec, **overrides) if overrides else spec


def observations_of(spec: SimulationSpec, views: SimulatedViews, intrinsics: CameraIntrinsics | None = None):
    """The estimator's input for simulated views (intrinsics default to the truth)."""
    from lps_gui.core.estimator.observations import Observations

    return Observations(
        board=spec.rig.board,
        mounted=None if spec.layout is None else spec.layout.targets,
        intrinsics=intrinsics or spec.rig.intrinsics,
        corners_px=views.corners_px,
        target_mm=[s.target_mm for s in views.stops],
        direction=[1.0 if s.direction == "+" else -1.0 for s in views.stops],
        run=[s.run for s in views.stops],
        index=[s.index for s in views.stops],
        source=f"simulation {spec.name}",
    )


# ----------------------------------------------------------------------------- rig descriptions

def spec_to_dict(spec: SimulationSpec, distance_mm: float | None = None) -> dict[str, Any]:
    """A JSON-ready rig description of ``spec`` (what ``lps simulate --rig`` reads)."""
    from lps_gui.core.geometry.rotation import log_so3

    rig = spec.rig
    intr = rig.intrinsics
    return {
        "name": spec.name,
        "board": {"type": rig.board.type, "inner_corners": [rig.board.cols, rig.board.rows], "square_mm": rig.board.square_mm},
        "intrinsics": {"image_size": list(intr.image_size), "fx": intr.fx, "fy": intr.fy, "cx": intr.cx, "cy": intr.cy,
                       "dist": intr.cv_dist.tolist()},
        "camera_pose": {"rvec_cam_board": log_so3(rig.R_cam_board).tolist(), "C0_board_mm": rig.C0_board.tolist(),
                        "u_board": rig.u_board.tolist()},
        "stage_errors": rig.errors.to_dict(),
        "plan": spec.plan.to_dict(),
        "noise_px": spec.noise_px,
        "noise_clip_px": spec.noise_clip_px,
        "missing_fraction": spec.missing_fraction,
        "replaced_views": list(spec.replaced_views),
        "bumped_views": list(spec.bumped_views),
        "bump_mrad": spec.bump_mrad,
        "seed": spec.seed,
    }


def spec_from_dict(d: dict[str, Any], source: str = "rig description") -> SimulationSpec:
    """Inverse of :func:`spec_to_dict`; a camera pose may instead be given as
    ``{"distance_mm": D, "tilt_deg": [..], "axis_misalignment_deg": [..]}``."""
    try:
        b = d["board"]
        board = Board(cols=int(b["inner_corners"][0]), rows=int(b["inner_corners"][1]), square_mm=float(b["square_mm"]),
                      type=b.get("type", "chessboard"))
        i = d["intrinsics"]
        intr = CameraIntrinsics.from_values(tuple(i["image_size"]), i["fx"], i["fy"], i["cx"], i["cy"], tuple(i.get("dist", [0] * 5)))
        plan = Plan.from_dict(d.get("plan", {}))
        errors = StageErrorModel.from_dict(d.get("stage_errors"))
        pose = d.get("camera_pose", {"distance_mm": 600.0})
        if "distance_mm" in pose:
            t = plan.targets()
            rig = Rig.facing_board(board, intr, float(pose["distance_mm"]), (t[0], t[-1]), errors,
                                   tuple(pose.get("tilt_deg", (2.0, -3.0, 1.0))), tuple(pose.get("axis_misalignment_deg", (0.5, -0.3))))
        else:
            u = np.asarray(pose["u_board"], dtype=float)
            rig = Rig(board, intr, exp_so3(np.asarray(pose["rvec_cam_board"], dtype=float)),
                      np.asarray(pose["C0_board_mm"], dtype=float), u / np.linalg.norm(u), errors)
        return SimulationSpec(
            name=str(d.get("name", "custom")),
            rig=rig,
            plan=plan,
            noise_px=float(d.get("noise_px", 0.1)),
            noise_clip_px=d.get("noise_clip_px"),
            missing_fraction=float(d.get("missing_fraction", 0.0)),
            replaced_views=tuple(int(v) for v in d.get("replaced_views", ())),
            bumped_views=tuple(int(v) for v in d.get("bumped_views", ())),
            bump_mrad=float(d.get("bump_mrad", 3.0)),
            seed=int(d.get("seed", 0)),
        )
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputError(f"{source}: {type(exc).__name__} {exc}; start from `lps simulate --write-rig rig.json`") from exc


def board_plane_positions(rig: Rig, pose: TruePose) -> np.ndarray:
    """The true positions at the board plane: the board centre's line of sight along its least-squares line (mm).

    The LPS model holds the camera's orientation constant, so a carriage
    rotation about an axis across the view shifts the image like a translation
    of (board distance x angle): what a camera measures is the displacement at
    the board plane, an Abbe offset equal to the distance. Per view, the board
    centre X0 sits at b_i = R_i X0 + t_i in the true camera frame; a camera of
    the rig's nominal orientation R0 sees it there from D_i = X0 - R0^T b_i
    (exact, any angle; to first order C_i + w_i x (X0 - C_i), the straightness
    truth's :func:`board_plane_straightness`). The positions are the D_i along
    the least-squares line through all of them (ISO 230-1's reference line,
    oriented as the axis), offset so a path without angles and straightness
    gives ``pose.axis_mm``. A roll moves D across the motion (distance x roll),
    so the line is not the axis direction: along the axis direction a curved
    path would read its lateral excursion into the positions. Independent of
    any solver. (It was the line model's own fit of the true poses, one unknown
    per view: that fit follows neither a roll's sideways path nor a tilt's
    perspective, and read them into the positions, 13 um RMS on the honesty
    campaign's ``motions`` stage.)
    """
    from lps_gui.core.models.constant_orientation import board_plane_displacements, path_direction

    R, t = rig.camera_poses(pose)
    D = board_plane_displacements(R, t, rig.board.object_points().mean(axis=0), rig.R_cam_board)
    a = path_direction(D, np.ones(len(D), bool), rig.u_board)
    return (D - rig.C0_board[None, :]) @ a


def board_plane_straightness(rig: Rig, pose: TruePose) -> tuple[np.ndarray, np.ndarray]:
    """Truth for the constant-orientation straightness and image rotation (SPEC 11).

    Returns the displacement at the board centre along v1, v2 (K, 2) um, not
    yet relative to a line, and the camera's rotation about its optical axis
    (K,) urad: D = C + w x (X0 - C) (first order in the carriage rotation w),
    independent of any solver; equals ``pose.straightness_um`` plus the
    line's offset without angular errors.
    """
    from lps_gui.core.models.constant_orientation import board_plane_offsets

    R, t = rig.camera_poses(pose)
    C = -np.einsum("kji,kj->ki", R, t)
    F = rig.frame()
    w = 1e-6 * np.asarray(pose.angles_urad, dtype=float) @ F.T
    X0 = rig.board.object_points().mean(axis=0)
    D = board_plane_offsets(C, w, X0)
    return 1e3 * D @ F[:, 1:], 1e6 * w @ rig.R_cam_board[2]
