"""ChArUco boards (cv2.aruco): corners of a partly visible board, each identified by its markers.

A :class:`Board` of type ``charuco`` with ``inner_corners`` (cols, rows) has
(cols+1) x (rows+1) squares; ChArUco corner id r*cols + c is chessboard
corner (r, c) at ((c+1) s, (r+1) s) in OpenCV's frame, i.e. exactly SPEC 2's
corner (r, c) shifted by one square, so ids map one-to-one to our indices
and views never flip.
"""
from __future__ import annotations

import cv2
import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError

DEFAULT_DICTIONARY = "DICT_5X5_1000"
MIN_CORNERS = 6  # fewer identified corners do not determine a homography reliably


def aruco_board(board: Board, first_marker: int = 0) -> "cv2.aruco.CharucoBoard":
    """The cv2.aruco.CharucoBoard matching ``board`` (marker size defaults to 70 % of a square).

    ``first_marker``: the board's markers are ids first_marker, first_marker + 1, ... (a target of a row, SPEC 13).
    """
    name = board.dictionary or DEFAULT_DICTIONARY
    code = getattr(cv2.aruco, name, None)
    if not isinstance(code, int):
        raise InputError(f"board: unknown ArUco dictionary {name!r}; use e.g. {DEFAULT_DICTIONARY}")
    marker_mm = board.marker_mm or 0.7 * board.square_mm
    if not 0 < marker_mm < board.square_mm:
        raise InputError(f"board: marker_mm {marker_mm} must be between 0 and square_mm {board.square_mm}")
    dictionary = cv2.aruco.getPredefinedDictionary(code)
    size = (board.cols + 1, board.rows + 1)
    if first_marker == 0:
        return cv2.aruco.CharucoBoard(size, board.square_mm, marker_mm, dictionary)
    ids = np.arange(first_marker, first_marker + size[0] * size[1] // 2, dtype=np.int32)
    return cv2.aruco.CharucoBoard(size, board.square_mm, marker_mm, dictionary, ids)


def board_image(board: Board, px_per_square: int = 40, margin_px: int = 40, first_marker: int = 0) -> np.ndarray:
    """A printable 8-bit image of the ChArUco board (for the user, and for tests)."""
    size = ((board.cols + 1) * px_per_square + 2 * margin_px, (board.rows + 1) * px_per_square + 2 * margin_px)
    return aruco_board(board, first_marker).generateImage(size, marginSize=margin_px)


def detect_charuco(image: np.ndarray, board: Board) -> tuple[np.ndarray | None, str]:
    """ChArUco corners, shape (N, 2) px in SPEC order with NaN where not seen, or (None, reason)."""
    image = grey(image)
    detector = cv2.aruco.CharucoDetector(aruco_board(board))
    corners, ids, _, _ = detector.detectBoard(image)
    if ids is None or len(ids) < MIN_CORNERS:
        seen = 0 if ids is None else len(ids)
        return None, f"ChArUco board not found ({seen} corners identified, need {MIN_CORNERS}); check dictionary and sizes in board.json"
    return refined_corners(image, board, ids, corners), ""


def grey(image: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


def refined_corners(image: np.ndarray, board: Board, ids: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(N, 2) px in SPEC order, NaN where not seen, refined like chessboard corners.

    The detector's own refinement is coarse; the window is sized from the
    corner spacing so the markers stay out of it.
    """
    out = np.full((board.n_corners, 2), np.nan)
    out[ids.ravel()] = corners.reshape(-1, 2)
    grid = out.reshape(board.rows, board.cols, 2)
    step = np.linalg.norm(np.diff(grid, axis=1), axis=-1)  # NaN where a neighbour is missing
    if np.isfinite(step).any():
        gap = (board.square_mm - (board.marker_mm or 0.7 * board.square_mm)) / (2 * board.square_mm)
        half = int(np.clip(round(0.8 * gap * np.nanmedian(step)), 2, 10))
        pts = corners.reshape(-1, 1, 2).astype(np.float32)
        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 40, 1e-3)
        out[ids.ravel()] = cv2.cornerSubPix(image, pts, (half, half), (-1, -1), crit).reshape(-1, 2)
    return out
