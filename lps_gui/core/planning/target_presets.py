"""Simulation presets of target rows and constellations (SPEC 13): the whole travel of the paper's stage.

``paper-row``: the paper's X axis, 1524 mm in 121 stops of 12.7 mm, six 10x7
ChArUco targets of 30 mm squares at 340 mm pitch, 800 mm from the paper's
camera (8 mm lens on 3.45 um pixels, 1920 x 1080), 0.1 px. ``small-row``: a
fast row for tests (640 x 480, three 7x5 targets, 18 stops). ``small-stitched``: one such
board moved along 220 mm in three overlapping segments (18 stops).
``paper-constellation`` (planar): a 1524 x 1016 mm grid of 13 x 9 stops
against a 6 x 4 constellation. Every target but the first is mounted with
random errors (10 mrad, 2 mm); the stage has positioning errors (scale,
periodic, repeatability) and no angular or straightness errors: the row model
holds one orientation and a straight line (plane), so what it measures is
the positioning error along the travel. The camera faces the middle of the
layout when the stage is in the middle of its travel; the views at the ends
see the outer targets cut by the image border.

:mod:`lps_gui.core.truth.simulate` registers these presets in its tables at import.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout, row_layout
from lps_gui.core.geometry.targets import Target, pack_targets
from lps_gui.core.models.lps_model import unit
from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.segments import stitched_segments
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulation_spec import SimulationSpec
from lps_gui.core.truth.stage_errors import PlanarErrorModel, StageErrorModel

ROW_CAMERA = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 959.5, 539.5,
                                          dist=(-0.169, 0.111, -0.0007, -0.00002, -0.02))  # 8 mm on 3.45 um pixels
ROW_BOARD = Board(10, 7, 30.0, type="charuco", marker_mm=22.0)
SMALL_CAMERA = CameraIntrinsics.from_values((640, 480), 600.0, 600.0, 319.5, 239.5, dist=(-0.12, 0.08, 0.0, 0.0, 0.0))
SMALL_BOARD = Board(7, 5, 20.0, type="charuco", marker_mm=15.0)
MOUNT_TILT_RAD = 0.01
MOUNT_OFFSET_MM = 2.0
CAMERA_TILT_DEG = (1.0, -1.5, 0.5)
MISALIGNMENT_DEG = (0.3, -0.2)


def row_errors() -> StageErrorModel:
    """Positioning errors of a lead-screw axis, without angular or straightness errors."""
    return StageErrorModel(scale_ppm=25.0, periodic_um=4.0, pitch_mm=25.4, repeatability_um=1.0)


def layout_centre(layout: TargetLayout) -> np.ndarray:
    """The middle of the targets' corners in the world frame (3,)."""
    _, world, _ = layout.points()
    return 0.5 * (world.min(axis=0) + world.max(axis=0))


def row_rig(layout: TargetLayout, intrinsics: CameraIntrinsics, distance_mm: float, travel_mm: tuple[float, float],
            errors: StageErrorModel) -> Rig:
    """A camera moving along the row (world x), slightly tilted and misaligned, facing the row's middle at
    the middle of the travel."""
    R = exp_so3(np.deg2rad(np.asarray(CAMERA_TILT_DEG)))
    C_mid = layout_centre(layout) - distance_mm * (R.T @ np.array([0.0, 0.0, 1.0]))
    a, b = np.deg2rad(MISALIGNMENT_DEG)
    u = unit(np.array([np.cos(a) * np.cos(b), np.sin(a), np.sin(b)]))
    return Rig(layout.targets[0].board, intrinsics, R, C_mid - 0.5 * (travel_mm[0] + travel_mm[1]) * u, u, errors)


def row_spec(name: str, board: Board, intrinsics: CameraIntrinsics, n_targets: int, pitch_mm: float,
             distance_mm: float, plan: Plan, seed: int, noise_px: float, errors: StageErrorModel | None
             ) -> SimulationSpec:
    layout = row_layout(pack_targets([board] * n_targets), pitch_mm, MOUNT_TILT_RAD, MOUNT_OFFSET_MM, seed=seed)
    t = plan.targets()
    rig = row_rig(layout, intrinsics, distance_mm, (float(t[0]), float(t[-1])), errors or row_errors())
    return SimulationSpec(name, rig, plan, noise_px=noise_px, seed=seed, layout=layout)


def paper_row_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None,
                   plan: Plan | None = None, n_targets: int = 6) -> SimulationSpec:
    """The paper's X axis against a row of six targets (SPEC 13)."""
    plan = plan or Plan(start_mm=0.0, stop_mm=1524.0, step_mm=12.7)
    return row_spec("paper-row", ROW_BOARD, ROW_CAMERA, n_targets, 340.0, 800.0, plan, seed, noise_px, errors)


def small_row_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None,
                   plan: Plan | None = None) -> SimulationSpec:
    """A fast row for tests: three 7x5 targets of 20 mm at 170 mm pitch, 300 mm away, 18 stops over 340 mm."""
    plan = plan or Plan(start_mm=0.0, stop_mm=340.0, step_mm=20.0)
    return row_spec("small-row", SMALL_BOARD, SMALL_CAMERA, 3, 170.0, 300.0, plan, seed, noise_px, errors)


def small_stitched_spec(seed: int = 0, noise_px: float = 0.1, errors: StageErrorModel | None = None,
                        segments: int = 3, segment_stops: int = 6, overlap_stops: int = 3) -> SimulationSpec:
    """One board moved along the travel (SPEC 13 stitching), the small row's camera and board 300 mm away: stops
    20 mm apart in ``segments`` segments of ``segment_stops``, each repeating the last ``overlap_stops`` of the one
    before. Placement k of the board is target ``S{k}`` (the estimate's names) moved by hand (10 mrad, 2 mm off)
    to face the middle of its segment, which then spans 100 mm: the whole board stays in the 640 x 480 view."""
    step = 20.0
    n = segment_stops + (segments - 1) * (segment_stops - overlap_stops)
    base = Plan(start_mm=0.0, stop_mm=step * (n - 1), step_mm=step)
    plan = replace(base, segments=stitched_segments(base.targets(), segment_stops, overlap_stops))
    placements = [Target(f"S{k}", SMALL_BOARD, 0) for k in range(segments)]  # one board: the same markers
    layout = row_layout(placements, step * (segment_stops - overlap_stops), MOUNT_TILT_RAD, MOUNT_OFFSET_MM, seed=seed)
    rig = row_rig(layout, SMALL_CAMERA, 300.0, (0.0, step * (n - 1)), errors or row_errors())
    return SimulationSpec("small-stitched", rig, plan, noise_px=noise_px, seed=seed, layout=layout)


def constellation_errors(squareness_urad: float = 150.0) -> PlanarErrorModel:
    """An out-of-square gantry with positioning errors on both axes (no angular or straightness errors)."""
    return PlanarErrorModel(x=StageErrorModel(scale_ppm=40.0, periodic_um=3.0, pitch_mm=25.4, repeatability_um=0.5),
                            y=StageErrorModel(scale_ppm=-30.0, periodic_um=2.0, pitch_mm=20.0, repeatability_um=0.5),
                            squareness_urad=squareness_urad)


def paper_constellation_spec(seed: int = 0, noise_px: float = 0.1, errors: PlanarErrorModel | None = None,
                             plan: Plan | None = None, grid: tuple[int, int] = (6, 4)) -> SimulationSpec:
    """The paper's 1524 x 1016 mm XY stage (13 x 9 stops) against a 6 x 4 constellation, 800 mm away."""
    plan = plan or Plan.xy(start_mm=(0.0, 0.0), stop_mm=(1524.0, 1016.0), step_mm=(127.0, 127.0))
    n = grid[0] * grid[1]
    half = n // 2  # 24 targets of 44 markers need two dictionaries of 1000 ids
    second = pack_targets([replace(ROW_BOARD, dictionary="DICT_6X6_1000")] * (n - half),
                          [f"T{j}" for j in range(half, n)])
    targets = pack_targets([ROW_BOARD] * half) + second
    rng = np.random.default_rng(seed)
    jj, ii = np.meshgrid(np.arange(grid[0]), np.arange(grid[1]))
    p = np.stack([340.0 * jj.ravel(), 300.0 * ii.ravel(), np.zeros(jj.size)], axis=1)
    p[1:] += rng.normal(0.0, MOUNT_OFFSET_MM, (len(targets) - 1, 3))
    Q = np.stack([np.eye(3)] + [exp_so3(rng.normal(0.0, MOUNT_TILT_RAD, 3)) for _ in targets[1:]])
    layout = TargetLayout(tuple(targets), Q, p)
    R = exp_so3(np.deg2rad(np.asarray(CAMERA_TILT_DEG)))
    C_mid = layout_centre(layout) - 800.0 * (R.T @ np.array([0.0, 0.0, 1.0]))
    E = exp_so3(np.deg2rad(np.array([MISALIGNMENT_DEG[0], MISALIGNMENT_DEG[1], 0.2])))  # columns e_x, e_y, e_n
    t = plan.targets()
    centre = 0.5 * (t.min(axis=0) + t.max(axis=0))
    rig = Rig(ROW_BOARD, ROW_CAMERA, R, C_mid - E[:, :2] @ centre, E, errors or constellation_errors())
    return SimulationSpec("paper-constellation", rig, plan, noise_px=noise_px, seed=seed, layout=layout)


TARGET_PRESETS = {"paper-row": paper_row_spec, "small-row": small_row_spec}
PLANAR_TARGET_PRESETS = {"paper-constellation": paper_constellation_spec}
