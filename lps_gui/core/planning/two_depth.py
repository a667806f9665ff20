"""Planning a two-depth constellation (SPEC 14): which targets, where, and the angular sigmas to expect.

Targets at two depths separate the camera's tilts from its translations; both
rows must fit the view at once. The far row fills the lower half of the image,
the near row the upper half, so each target is the largest printable square
whose rows fit half the view at its own distance (the near ones, closer,
smaller: the paper camera at 800 mm takes 30 mm squares far and 15 mm squares
300 mm nearer). The prediction is the estimator's own: the corners the rig
would see (:func:`lps_gui.core.truth.two_depth.two_depth_rig`, no stage errors, no
mounting errors), solved for every stop's pose with the targets
(:func:`lps_gui.core.models.pose_model.solve_poses` at the corner noise given) and
turned into the error motions' sigmas (:mod:`lps_gui.core.metrology.error_motions`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.metrology.error_motions import ANGULAR, error_motions
from lps_gui.core.models.pose_model import solve_poses
from lps_gui.core.planning.rows import MIN_SQUARE_PX, SQUARE_SIZES_MM
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.core.truth.two_depth import EDGE_PX, observe_stops, two_depth_rig
from lps_gui.errors import DegenerateGeometryError, InputError


@dataclass
class TwoDepthPlan:
    """A proposed two-depth layout and the sigmas it predicts per stop (centred: without the first stop's noise)."""

    distance_mm: float
    near_mm: float
    travel_mm: float
    stops: int
    far: Board
    near: Board
    n_far: int
    n_near: int
    far_pitch_mm: float
    near_pitch_mm: float
    angle_sigma_urad: dict[str, float]  # EAX, EBX, ECX: median centred sigma per stop
    single_view_urad: dict[str, float]  # what one view alone resolves (targets known), median
    positioning_sigma_um: float  # EXX at the camera centre, median centred
    square_px: tuple[float, float]  # far, near
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        def board(b: Board) -> dict[str, Any]:
            return {"inner_corners": [b.cols, b.rows], "square_mm": b.square_mm, "marker_mm": b.marker_mm}

        return {"distance_mm": self.distance_mm, "near_mm": self.near_mm, "travel_mm": self.travel_mm,
                "stops": self.stops, "far": {**board(self.far), "count": self.n_far, "pitch_mm": self.far_pitch_mm},
                "near": {**board(self.near), "count": self.n_near, "pitch_mm": self.near_pitch_mm},
                "angle_sigma_urad": self.angle_sigma_urad, "single_view_urad": self.single_view_urad,
                "positioning_sigma_um": self.positioning_sigma_um, "square_px": list(self.square_px),
                "notes": self.notes}

    def make_targets_commands(self) -> list[str]:
        """The two `lps make-targets` lines: the near row's markers start after the far row's."""
        far, near = self.far, self.near
        first = self.n_far * ((far.cols + 1) * (far.rows + 1) // 2)
        return [f"lps make-targets far --count {self.n_far} --inner-corners {far.cols}x{far.rows} "
                f"--square-mm {far.square_mm:g} --marker-mm {far.marker_mm:g} --prefix F",
                f"lps make-targets near --count {self.n_near} --inner-corners {near.cols}x{near.rows} "
                f"--square-mm {near.square_mm:g} --marker-mm {near.marker_mm:g} --first-marker {first} --prefix N"]


def row_board(intrinsics: CameraIntrinsics, distance_mm: float, inner_corners: tuple[int, int] = (10, 7),
              paper_squares: float = 0.0) -> Board:
    """The largest printable square whose corner rows (plus ``paper_squares`` of paper) fit half the view
    height at ``distance_mm`` (a little inside the image edge)."""
    reach_mm = (0.5 * intrinsics.image_size[1] - EDGE_PX) / intrinsics.fy * distance_mm
    cols, rows = inner_corners
    fits = [s for s in SQUARE_SIZES_MM if (rows - 1 + paper_squares) * s <= reach_mm]
    square = fits[-1] if fits else SQUARE_SIZES_MM[0]
    return Board(cols, rows, square, type="charuco", marker_mm=round(0.75 * square, 2))


def plan_two_depth(intrinsics: CameraIntrinsics, distance_mm: float, travel_mm: float, near_mm: float = 300.0,
                   stops: int = 121, noise_px: float = 0.1, inner_corners: tuple[int, int] = (10, 7)) -> TwoDepthPlan:
    """Propose a far and a near row for a travel and predict the angular sigmas per stop."""
    if not (distance_mm > 0 and travel_mm > 0 and noise_px > 0):
        raise InputError("plan-rig: the distance, the travel and the corner noise must be positive")
    if not 0 < near_mm < distance_mm - 50.0:
        raise InputError(f"plan-rig: --two-depth {near_mm:g} must put the near row between the camera and the far "
                         f"row (0 < NEAR < {distance_mm - 50.0:g} mm at --distance-mm {distance_mm:g})")
    if stops < 3:
        raise InputError("plan-rig: a two-depth plan needs at least 3 stops")
    far = row_board(intrinsics, distance_mm, inner_corners)
    near = row_board(intrinsics, distance_mm - near_mm, inner_corners, paper_squares=1.5)  # its paper clears the far row
    tr = two_depth_rig(travel_mm, distance_mm, near_mm, far, near, intrinsics, errors=StageErrorModel(),
                       mount_error_sigma=(0.0, 0.0))
    views = observe_stops(tr, np.linspace(0.0, travel_mm, stops), noise_px=0.0)
    try:
        sol = solve_poses(views.observations, intrinsics, noise_px=noise_px, max_iterations=5)
    except DegenerateGeometryError as exc:
        raise InputError(f"plan-rig: the proposed two-depth layout does not tie its targets ({exc}); "
                         "move the camera back") from None
    em = error_motions(sol, views.observations.targets_mm)
    n_far = sum(1 for t in tr.layout.targets if t.id.startswith("F"))
    pitch = np.diff(tr.layout.p[:, 0])
    square_px = (far.square_mm * intrinsics.fx / distance_mm, near.square_mm * intrinsics.fx / (distance_mm - near_mm))
    notes = []
    if min(square_px) < MIN_SQUARE_PX:
        notes.append(f"a near square is {min(square_px):.0f} px in the image: markers may not be read below "
                     f"{MIN_SQUARE_PX:.0f} px; bring the near row closer to the far one or use a longer lens")
    names = [em.names[n] for n in ANGULAR]
    return TwoDepthPlan(
        float(distance_mm), float(near_mm), float(travel_mm), int(stops), far, near, n_far,
        len(tr.layout.targets) - n_far, float(pitch[0]), float(pitch[n_far]) if len(pitch) > n_far else 0.0,
        {n: float(np.nanmedian(em.centred_sigmas[a])) for n, a in zip(names, ANGULAR)},
        {n: float(np.nanmedian(em.single_view_urad[:, k])) for k, n in enumerate(names)},
        float(np.nanmedian(em.centred_sigmas["positioning"])), square_px, notes)
