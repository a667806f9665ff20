"""Chessboard corners in one image, and tracked through an LPS session.

Full detection runs cv2.findChessboardCornersSB (on a half-size image when
the frame is large: 4x cheaper, same topology) and refines every corner with
cv2.cornerSubPix at full resolution, then without its pixel locking
(:mod:`lps_gui.camera.subpixel`). Between neighbouring frames of an LPS
session the board only shifts by a few pixels, so :class:`ChessboardTracker`
predicts the corners from the previous frame (shift measured by phase
correlation on a quarter-size image), refines them with cornerSubPix and
verifies the result (corner moved little, grid still regular, image still
sharp), falling back to full detection when verification fails. Tracking
keeps the corner order, so views never flip by 180 degrees; full detections
are oriented with SPEC section 2 (board +x to image right) or, when a
prediction exists, to agree with it.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lps_gui.camera.subpixel import polish_corners
from lps_gui.core.geometry.board import Board

SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 1e-3)


@dataclass(frozen=True)
class DetectionOptions:
    """Knobs of detection; the defaults suit 640x480 to 4K frames."""

    sb_max_width: int = 1280  # run findChessboardCornersSB at half size above this width
    track: bool = True  # predict from the previous frame instead of full detection
    max_move_frac: float = 0.45  # refined corner may move this fraction of the window from prediction
    grid_tol_frac: float = 0.12  # second difference of the grid, fraction of a square
    min_sharpness_ratio: float = 0.5  # sharpness relative to the last full detection
    homography_tol_frac: float = 0.05  # frame-to-frame homography residual, fraction of a square


@dataclass
class Detection:
    """What detection found in one image."""

    corners_px: np.ndarray | None  # shape (N, 2) SPEC order, or None
    method: str  # "track", "full" or "failed"
    reason: str = ""  # why it failed, or why tracking fell back
    sharpness: float = float("nan")


def sharpness(image: np.ndarray) -> float:
    """Focus figure: variance of the Laplacian of the half-size image (grey levels^2).

    Larger is sharper; compare frames of one scene (it scales with contrast),
    e.g. to focus a camera in the GUI or to notice a frame taken while moving.
    """
    grey = _grey(image)
    small = cv2.resize(grey, (grey.shape[1] // 2, grey.shape[0] // 2), interpolation=cv2.INTER_AREA)
    lap = cv2.Laplacian(small, cv2.CV_32F)
    return float(lap.var())


def _grey(image: np.ndarray) -> np.ndarray:
    if image.ndim == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return image


def square_px(corners_px: np.ndarray, board: Board) -> float:
    """Median distance between horizontally neighbouring corners, px."""
    grid = corners_px.reshape(board.rows, board.cols, 2)
    return float(np.median(np.linalg.norm(np.diff(grid, axis=1), axis=-1)))


def subpix_half_window(corners_px: np.ndarray, board: Board) -> int:
    """cornerSubPix half window: ~30 % of a square, so no neighbouring corner enters it."""
    return int(np.clip(round(0.3 * square_px(corners_px, board)), 2, 10))


def refine(image: np.ndarray, corners_px: np.ndarray, half_window: int) -> np.ndarray:
    """cornerSubPix on every corner (it converges from a rough guess), then the interpolation-free polish
    that removes its pixel locking (:func:`lps_gui.camera.subpixel.polish_corners`); (N, 2) -> (N, 2) float64."""
    pts = np.ascontiguousarray(corners_px, dtype=np.float32).reshape(-1, 1, 2)
    out = cv2.cornerSubPix(image, pts, (half_window, half_window), (-1, -1), SUBPIX_CRITERIA)
    return polish_corners(image, out.reshape(-1, 2).astype(np.float64), half_window)


def orient(corners_px: np.ndarray, board: Board, reference_px: np.ndarray | None = None) -> np.ndarray:
    """Put detected corners in SPEC 2 order.

    Without a reference, board +x (along a row) points to image right and the
    grid is right-handed in image coordinates (u right, v down), as when the
    camera faces the printed side. With a reference (a prediction), the
    candidate ordering closest to it wins, so tracked views never flip.
    """
    grid = corners_px.reshape(board.rows, board.cols, 2)
    candidates = [grid, grid[::-1, ::-1]]
    if board.rows == board.cols:
        candidates += [np.swapaxes(grid, 0, 1)[:, ::-1], np.swapaxes(grid, 0, 1)[::-1, :]]
    if reference_px is not None:
        ref = reference_px.reshape(board.rows, board.cols, 2)
        best = min(candidates, key=lambda g: float(np.nanmean(np.sum((g - ref) ** 2, axis=-1))))
        return best.reshape(-1, 2)
    for g in candidates:
        along_x = (g[:, -1] - g[:, 0]).mean(axis=0)
        along_y = (g[-1, :] - g[0, :]).mean(axis=0)
        if along_x[0] > 0 and along_x[0] * along_y[1] - along_x[1] * along_y[0] > 0:
            return g.reshape(-1, 2)
    g = grid if (grid[:, -1] - grid[:, 0]).mean(axis=0)[0] > 0 else grid[::-1, ::-1]
    return g[::-1].reshape(-1, 2)  # mirrored order: re-walk the rows to make it right-handed


def grid_irregularity(corners_px: np.ndarray, board: Board) -> float:
    """Largest second difference along rows and columns, in squares.

    Perspective and lens distortion bend the grid smoothly (a few % of a
    square); a corner refined onto the wrong feature breaks it by tens of %.
    """
    grid = corners_px.reshape(board.rows, board.cols, 2)
    worst = 0.0
    if board.cols >= 3:
        worst = max(worst, float(np.max(np.linalg.norm(grid[:, 2:] - 2 * grid[:, 1:-1] + grid[:, :-2], axis=-1))))
    if board.rows >= 3:
        worst = max(worst, float(np.max(np.linalg.norm(grid[2:] - 2 * grid[1:-1] + grid[:-2], axis=-1))))
    return worst / max(square_px(corners_px, board), 1e-9)


def _axes(corners_px: np.ndarray, board: Board) -> tuple[np.ndarray, np.ndarray]:
    g = corners_px.reshape(board.rows, board.cols, 2)
    return (g[:, -1] - g[:, 0]).mean(axis=0), (g[-1, :] - g[0, :]).mean(axis=0)


def same_ordering(a_px: np.ndarray, b_px: np.ndarray, board: Board) -> bool:
    """Do two views' corner grids run the same way (board +x alike, same handedness)?"""
    ax, ay = _axes(a_px, board)
    bx, by = _axes(b_px, board)
    cross_a = ax[0] * ay[1] - ax[1] * ay[0]
    cross_b = bx[0] * by[1] - bx[1] * by[0]
    return bool(ax @ bx > 0 and ay @ by > 0 and cross_a * cross_b > 0)


def frame_homography_residual(prev_px: np.ndarray, now_px: np.ndarray) -> float:
    """Largest distance (px) of a corner from the least-squares homography prev -> now.

    Between neighbouring LPS frames the corners move by a near-homography
    (a shift, slightly varied by distortion): residuals sit at the noise level
    (~0.1 px), a corner refined onto the wrong feature stands out by pixels.
    """
    H, _ = cv2.findHomography(prev_px.astype(np.float64), now_px.astype(np.float64), 0)
    if H is None:
        return float("inf")
    mapped = cv2.perspectiveTransform(prev_px.reshape(-1, 1, 2).astype(np.float64), H).reshape(-1, 2)
    return float(np.max(np.linalg.norm(mapped - now_px, axis=-1)))


def find_chessboard_sb(image: np.ndarray, board: Board, sb_max_width: int = 1280) -> np.ndarray | None:
    """findChessboardCornersSB, at half size for large frames; (N, 2) px unrefined, or None."""
    pattern = (board.cols, board.rows)
    if image.shape[1] > sb_max_width:
        small = cv2.resize(image, (image.shape[1] // 2, image.shape[0] // 2), interpolation=cv2.INTER_AREA)
        ok, corners = cv2.findChessboardCornersSB(small, pattern)
        if ok:
            return corners.reshape(-1, 2).astype(np.float64) * 2.0 + 0.5  # small pixel i covers 2i, 2i+1
    ok, corners = cv2.findChessboardCornersSB(image, pattern)
    return corners.reshape(-1, 2).astype(np.float64) if ok else None


def why_not_found(image: np.ndarray, board: Board) -> str:
    """A reason for a failed detection; names a visible board of another size when there is one.

    findChessboardCornersSB with CALIB_CB_LARGER grows a small seed pattern
    to what it can see (not always the whole board), so a size is only
    claimed when it exceeds the expected one along some axis.
    """
    small = image
    if image.shape[1] > 1280:
        small = cv2.resize(image, (image.shape[1] // 2, image.shape[0] // 2), interpolation=cv2.INTER_AREA)
    try:
        ok, _, meta = cv2.findChessboardCornersSBWithMeta(small, (3, 3), cv2.CALIB_CB_LARGER)
    except cv2.error:
        ok, meta = False, None
    expected = sorted((board.cols, board.rows))
    if ok and meta is not None:
        seen = sorted(meta.shape[:2])
        if seen[0] > expected[0] or seen[1] > expected[1]:
            return (
                f"board not found: a board with at least {seen[1]}x{seen[0]} inner corners is visible but "
                f"{board.cols}x{board.rows} was expected; check inner_corners in board.json"
            )
    return f"board not found ({board.cols}x{board.rows} inner corners): out of view, too blurred, or wrong board.json"


def detect_chessboard(
    image: np.ndarray,
    board: Board,
    reference_px: np.ndarray | None = None,
    sb_max_width: int = 1280,
) -> np.ndarray | None:
    """Full detection of ``board`` in ``image``: corners (N, 2) px in SPEC order, or None.

    For the GUI preview and as the fallback of tracking. ``reference_px``
    (N, 2), e.g. the previous view's corners, fixes the orientation.
    """
    grey = _grey(image)
    found = find_chessboard_sb(grey, board, sb_max_width)
    if found is None:
        return None
    found = orient(found, board, reference_px)
    return refine(grey, found, subpix_half_window(found, board))


class ChessboardTracker:
    """Detects the board in a sequence of frames, tracking it from frame to frame.

    Call :meth:`detect` with the frames in capture order. Keeps only the
    previous frame's corners and a quarter-size copy of its image.
    """

    def __init__(self, board: Board, options: DetectionOptions | None = None) -> None:
        self.board = board
        self.options = options or DetectionOptions()
        self._prev_px: np.ndarray | None = None  # shape (N, 2)
        self._prev_small: np.ndarray | None = None  # quarter-size float32 image
        self._window = None
        self._ref_sharpness: float | None = None
        self._half_window = 5
        self.n_tracked = 0
        self.n_full = 0
        self._last_failure: str | None = None

    def reset(self) -> None:
        self._prev_px = None
        self._prev_small = None

    def _small(self, image: np.ndarray) -> np.ndarray:
        h, w = image.shape
        small = cv2.resize(image, (w // 4, h // 4), interpolation=cv2.INTER_AREA).astype(np.float32)
        if self._window is None or self._window.shape != small.shape:
            self._window = cv2.createHanningWindow(small.shape[::-1], cv2.CV_32F)
        return small

    def _predict(self, small: np.ndarray) -> np.ndarray | None:
        if self._prev_px is None or self._prev_small is None or self._prev_small.shape != small.shape:
            return None
        (dx, dy), response = cv2.phaseCorrelate(self._prev_small, small, self._window)
        if not (np.isfinite(dx) and np.isfinite(dy)):
            return None
        return self._prev_px + 4.0 * np.array([dx, dy])

    def _verify(self, image: np.ndarray, predicted: np.ndarray, refined: np.ndarray, sharp: float) -> str:
        """Empty string when the tracked corners are trustworthy, else the reason."""
        opt = self.options
        hw = self._half_window
        move = np.linalg.norm(refined - predicted, axis=-1)
        if float(move.max()) > opt.max_move_frac * (2 * hw + 1):
            return "a corner moved too far from its prediction"
        if grid_irregularity(refined, self.board) > opt.grid_tol_frac:
            return "corner grid irregular"
        if self._prev_px is not None:
            if not same_ordering(self._prev_px, refined, self.board):
                return "corner ordering changed"
            if frame_homography_residual(self._prev_px, refined) > max(0.5, opt.homography_tol_frac * square_px(refined, self.board)):
                return "corners do not follow a homography from the previous frame"
        if self._ref_sharpness and sharp < opt.min_sharpness_ratio * self._ref_sharpness:
            return "image blurred compared with the last full detection"
        return ""

    def _inside(self, image: np.ndarray, predicted: np.ndarray) -> bool:
        h, w = image.shape
        m = self._half_window + 2
        return bool(np.all(predicted >= m) and np.all(predicted[:, 0] < w - m) and np.all(predicted[:, 1] < h - m))

    def detect(self, image: np.ndarray) -> Detection:
        """Corners of the board in the next frame (N, 2) SPEC order, or a failure reason."""
        grey = _grey(image)
        small = self._small(grey)
        sharp = float(cv2.Laplacian(small, cv2.CV_32F).var())
        predicted = self._predict(small) if self.options.track else None
        reason = ""
        if predicted is not None and not self._inside(grey, predicted):
            reason = "corners near the image border"
        elif predicted is not None:
            refined = refine(grey, predicted, self._half_window)
            reason = self._verify(grey, predicted, refined, sharp)
            if not reason:
                self._prev_px, self._prev_small = refined, small
                self.n_tracked += 1
                return Detection(refined, "track", "", sharp)
        found = find_chessboard_sb(grey, self.board, self.options.sb_max_width)
        if found is None:
            self.reset()
            if self._last_failure is None:  # diagnosing costs another SB run: once per failing stretch
                self._last_failure = why_not_found(grey, self.board)
            return Detection(None, "failed", self._last_failure, sharp)
        self._last_failure = None
        found = orient(found, self.board, predicted if predicted is not None else None)
        self._half_window = subpix_half_window(found, self.board)
        refined = refine(grey, found, self._half_window)
        self._prev_px, self._prev_small = refined, small
        self._ref_sharpness = sharp
        self.n_full += 1
        return Detection(refined, "full", reason, sharp)
