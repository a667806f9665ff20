"""Planning a target row or constellation for a travel longer than one board's view (SPEC 13).

One board at a usable distance covers about the camera's field of view; the
whole travel of a long axis needs targets along it. From the camera, the
distance and the travel we propose a layout (target size, count, pitch) and
predict the sigma per stop under the estimator's own model: the corners the
rig would see, noise free, solved by :func:`solve_targets` with the corner
noise given. The layout rules:

- target height about 60 % of the view height (room for mounting and the
  camera's height above the row), the square a printable size;
- neighbours 3 % of a target width apart (at least 10 mm), so that every
  view sees two of them and ties them;
- enough targets that the view at either end of the travel is at least
  three-quarters covered.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.target_rig import TargetLayout, observe
from lps_gui.core.geometry.targets import Target, pack_targets
from lps_gui.core.models.target_model import TargetObservations, solve_targets
from lps_gui.errors import DegenerateGeometryError, InputError

SQUARE_SIZES_MM = (5.0, 7.5, 10.0, 12.5, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0, 60.0, 80.0, 100.0)
MIN_SQUARE_PX = 30.0  # a 5x5 marker needs about 3 px per cell to be read
EDGE_MARGIN_PX = 10.0
DITHER_PX = 1e-6


@dataclass
class RowPlan:
    """A proposed layout and what it predicts."""

    distance_mm: float
    travel_mm: tuple[float, ...]
    view_mm: tuple[float, float]  # field of view at the distance (w, h)
    board: Board
    grid: tuple[int, int]  # targets along X, along Y
    pitch_mm: tuple[float, float]
    stops: int
    sigma_um_median: float  # per coordinate, relative to the first stop (as lps estimate reports)
    sigma_um_max: float
    centred_sigma_um_median: float  # without the first stop's own noise
    square_px: float
    notes: list[str] = field(default_factory=list)
    stops_per_axis: tuple[int, ...] = ()

    @property
    def n_targets(self) -> int:
        return self.grid[0] * self.grid[1]

    def geometry(self) -> tuple[TargetLayout, np.ndarray, np.ndarray, np.ndarray]:
        """The nominal layout and views of this plan: layout, R (3, 3), t (K, 3) and the stops' coordinates (K, D)."""
        return row_geometry(self.board, self.grid, self.pitch_mm, self.distance_mm, self.travel_mm, self.stops_per_axis)

    def make_targets_command(self) -> str:
        """The `lps make-targets` line that prints this layout's targets."""
        b = self.board
        return (f"lps make-targets row --count {self.n_targets} --inner-corners {b.cols}x{b.rows} "
                f"--square-mm {b.square_mm:g} --marker-mm {b.marker_mm:g}")

    def to_dict(self) -> dict:
        b = self.board
        return {"distance_mm": self.distance_mm, "travel_mm": list(self.travel_mm), "view_mm": list(self.view_mm),
                "target": {"inner_corners": [b.cols, b.rows], "square_mm": b.square_mm, "marker_mm": b.marker_mm},
                "targets": [self.grid[0], self.grid[1]], "n_targets": self.n_targets, "pitch_mm": list(self.pitch_mm),
                "stops": self.stops, "sigma_um_median": self.sigma_um_median, "sigma_um_max": self.sigma_um_max,
                "centred_sigma_um_median": self.centred_sigma_um_median, "square_px": self.square_px,
                "notes": self.notes}


def view_mm(intrinsics: CameraIntrinsics, distance_mm: float) -> tuple[float, float]:
    w, h = intrinsics.image_size
    return (w / intrinsics.fx * distance_mm, h / intrinsics.fy * distance_mm)


def propose_board(intrinsics: CameraIntrinsics, distance_mm: float, inner_corners: tuple[int, int] = (10, 7)) -> Board:
    """The largest printable square whose target fills about 60 % of the view height (and 60 % of its width)."""
    W, H = view_mm(intrinsics, distance_mm)
    cols, rows = inner_corners
    limit = min(0.6 * H / (rows + 1), 0.6 * W / (cols + 1))
    fits = [s for s in SQUARE_SIZES_MM if s <= limit]
    square = fits[-1] if fits else SQUARE_SIZES_MM[0]
    return Board(cols, rows, square, type="charuco", marker_mm=round(0.75 * square, 2))


def _count(travel: float, view: float, width: float, pitch: float) -> int:
    return max(2, math.ceil((travel + 0.5 * view - width) / pitch) + 1) if travel > 0 else 1


def plan_row(intrinsics: CameraIntrinsics, distance_mm: float, travel_mm: tuple[float, ...], stops: tuple[int, ...] | None = None,
             noise_px: float = 0.1, board: Board | None = None, wanted_sigma_um: float | None = None) -> RowPlan:
    """Propose a row (one travel) or a constellation (two) and predict the sigma per stop."""
    if not distance_mm > 0 or not noise_px > 0:
        raise InputError("plan-rig: the camera distance and the corner noise must be positive")
    if not 1 <= len(travel_mm) <= 2 or not all(t > 0 for t in travel_mm):
        raise InputError("plan-rig: --travel (and --travel-y) must be positive lengths in mm")
    board = board or propose_board(intrinsics, distance_mm)
    W, H = view_mm(intrinsics, distance_mm)
    bw, bh = (board.cols + 1) * board.square_mm, (board.rows + 1) * board.square_mm
    gap_x, gap_y = max(10.0, 0.03 * bw), max(10.0, 0.03 * bh)
    pitch = (math.ceil((bw + gap_x) / 10.0) * 10.0, math.ceil((bh + gap_y) / 10.0) * 10.0)
    D = len(travel_mm)
    grid = (_count(travel_mm[0], W, bw, pitch[0]), _count(travel_mm[1], H, bh, pitch[1]) if D == 2 else 1)
    if grid[0] * grid[1] > 400:
        raise InputError(f"plan-rig: {grid[0] * grid[1]} targets would be needed; move the camera back or use a longer lens")
    stops = tuple(stops or ((121,) if D == 1 else (13, 9)))
    if len(stops) != D or min(stops) < 3:
        raise InputError("plan-rig: give at least 3 stops along each travelled axis")
    layout, R, t, targets_mm = row_geometry(board, grid, pitch, distance_mm, travel_mm, stops)
    # a noise-free view can be exactly affine, where planar PnP's decomposition (IPPE) gives NaN and the
    # initializer drops the view: a dither far below any corner noise avoids it and changes no sigma
    uv = observe(layout, intrinsics, R, t, noise_px=DITHER_PX, border_px=EDGE_MARGIN_PX)
    obs = TargetObservations(list(layout.targets), uv, targets_mm, [f"stop{i}" for i in range(len(t))])
    try:
        sol = solve_targets(obs, intrinsics, noise_px=noise_px, max_iterations=5)
    except DegenerateGeometryError as exc:
        raise InputError(f"plan-rig: the proposed layout does not tie its targets ({exc}); move the camera back") from None
    sig = sol.sigma_s[1:][sol.used[1:]] * 1e3  # the stops that see a target (all, on a proposed layout)
    square_px = board.square_mm * intrinsics.fx / distance_mm
    notes = []
    if square_px < MIN_SQUARE_PX:
        notes.append(f"a square is {square_px:.0f} px in the image: markers may not be read below {MIN_SQUARE_PX:.0f} px; "
                     "move the camera closer or use a longer lens")
    if wanted_sigma_um is not None and np.median(sig) > wanted_sigma_um:
        notes.append(f"the median sigma {np.median(sig):.2f} um misses the wanted {wanted_sigma_um:g} um: "
                     "move the camera closer (the layout shrinks with it) or use a longer lens")
    return RowPlan(float(distance_mm), tuple(float(v) for v in travel_mm), (W, H), board, grid, pitch,
                   int(np.prod(stops)), float(np.median(sig)), float(np.max(sig)),
                   float(np.median(sol.sigma_centred[sol.used]) * 1e3), float(square_px), notes, stops)


def row_geometry(board: Board, grid: tuple[int, int], pitch: tuple[float, float], distance_mm: float,
                 travel_mm: tuple[float, ...], stops: tuple[int, ...]) -> tuple[TargetLayout, np.ndarray, np.ndarray, np.ndarray]:
    """The nominal layout of a plan and its views (R, t, stop coordinates): what the planner and its tests observe."""
    layout = _layout(board, grid, pitch)
    t, R, targets_mm = _views(layout, board, grid, pitch, distance_mm, travel_mm, stops)
    return layout, R, t, targets_mm


def _layout(board: Board, grid: tuple[int, int], pitch: tuple[float, float]) -> TargetLayout:
    targets: list[Target] = pack_targets([board] * (grid[0] * grid[1]))
    jj, ii = np.meshgrid(np.arange(grid[0]), np.arange(grid[1]))
    p = np.stack([pitch[0] * jj.ravel(), pitch[1] * ii.ravel(), np.zeros(jj.size)], axis=1)
    return TargetLayout(tuple(targets), np.tile(np.eye(3), (len(targets), 1, 1)), p)


def _views(layout: TargetLayout, board: Board, grid, pitch, distance_mm, travel_mm, stops):
    """Camera translations of every stop: facing the targets, centred on the layout, the travel about its middle."""
    span = np.array([(grid[0] - 1) * pitch[0] + board.size_mm[0], (grid[1] - 1) * pitch[1] + board.size_mm[1]])
    centre = span / 2.0
    axes = [np.linspace(-t / 2.0, t / 2.0, n) for t, n in zip(travel_mm, stops)]
    if len(axes) == 1:
        xy = np.stack([axes[0], np.zeros_like(axes[0])], axis=1)
        targets_mm = (axes[0] - axes[0][0])[:, None]
    else:
        gx, gy = np.meshgrid(*axes)
        xy = np.stack([gx.ravel(), gy.ravel()], axis=1)
        targets_mm = xy - xy[0]
    C = np.c_[centre + xy, np.full(len(xy), -float(distance_mm))]
    R = np.eye(3)
    return -C @ R.T, R, targets_mm


MIN_DISTANCE_MM, MAX_DISTANCE_MM, DISTANCE_STEP_MM = 200.0, 5000.0, 50.0


def propose_row(intrinsics: CameraIntrinsics, travel_mm: tuple[float, ...], wanted_sigma_um: float,
                stops: tuple[int, ...] | None = None, noise_px: float = 0.1, start_mm: float = 800.0) -> RowPlan:
    """The farthest camera distance (in steps of 50 mm) whose layout meets the wanted median sigma per stop.

    Farther means larger and fewer targets; the sigma grows with the distance (the view covers more
    travel per pixel), so the answer is the end of a bracket. The next distance is the secant of the
    two latest predictions (the sigma is close to affine in the distance), kept inside the bracket.
    """
    if not wanted_sigma_um > 0:
        raise InputError(f"plan-rig: the wanted sigma must be positive, got {wanted_sigma_um}")
    plans: dict[float, RowPlan] = {}

    def at(d: float) -> RowPlan:
        d = float(np.clip(DISTANCE_STEP_MM * round(d / DISTANCE_STEP_MM), MIN_DISTANCE_MM, MAX_DISTANCE_MM))
        if d not in plans:
            plans[d] = plan_row(intrinsics, d, travel_mm, stops, noise_px)
        return plans[d]

    ok, bad = 0.0, math.inf  # the farthest distance meeting the wanted sigma, the nearest missing it
    d = start_mm
    for _ in range(12):
        p = at(d)
        d = p.distance_mm
        if p.sigma_um_median <= wanted_sigma_um:
            ok = max(ok, d)
        else:
            bad = min(bad, d)
        if bad - ok <= DISTANCE_STEP_MM or (ok >= MAX_DISTANCE_MM) or bad <= MIN_DISTANCE_MM:
            break
        tried = list(plans)  # in the order evaluated
        if len(tried) >= 2:
            d0, d1 = tried[-2:]
            s0, s1 = plans[d0].sigma_um_median, plans[d1].sigma_um_median
            guess = d1 + (wanted_sigma_um - s1) * (d1 - d0) / (s1 - s0) if s1 != s0 else 0.5 * (d0 + d1)
        else:
            guess = d * wanted_sigma_um / p.sigma_um_median
        lo, hi = ok + DISTANCE_STEP_MM, (bad - DISTANCE_STEP_MM) if bad < math.inf else MAX_DISTANCE_MM
        d = float(np.clip(guess, lo, hi)) if lo <= hi else lo
    if ok == 0.0:
        nearest = plans[min(plans)]
        raise InputError(f"plan-rig: {nearest.distance_mm:g} mm away (the nearest tried) the median sigma per stop is "
                         f"{nearest.sigma_um_median:.2f} um, more than the wanted {wanted_sigma_um:g} um; "
                         "use a longer lens or a camera with more pixels")
    best = plans[ok]
    if ok >= MAX_DISTANCE_MM:
        best.notes.append(f"the wanted sigma is met {MAX_DISTANCE_MM:g} mm away, the farthest distance proposed")
    return best
