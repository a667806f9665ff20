"""board.json (SPEC 7): ``{"type": "chessboard", "inner_corners": [cols, rows], "square_mm": 10.0}``."""
from __future__ import annotations

from pathlib import Path
from typing import Any

from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError
from lps_gui.io.jsonfile import read_json, write_json
from lps_gui.io.value_checks import check_board_values


def board_from_dict(d: dict[str, Any], source: str = "board") -> Board:
    check_board_values(d, source)
    try:
        cols, rows = (int(v) for v in d["inner_corners"])
        return Board(
            cols=cols,
            rows=rows,
            square_mm=float(d["square_mm"]),
            type=str(d.get("type", "chessboard")),
            marker_mm=None if d.get("marker_mm") is None else float(d["marker_mm"]),
            dictionary=d.get("dictionary"),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(
            f"{source}: expected {{\"type\": \"chessboard\", \"inner_corners\": [cols, rows], \"square_mm\": s}} ({exc})"
        ) from exc


def board_to_dict(board: Board) -> dict[str, Any]:
    d: dict[str, Any] = {"type": board.type, "inner_corners": [board.cols, board.rows], "square_mm": board.square_mm}
    if board.marker_mm is not None:
        d["marker_mm"] = board.marker_mm
    if board.dictionary is not None:
        d["dictionary"] = board.dictionary
    return d


def read_board(path: Path | str) -> Board:
    return board_from_dict(read_json(path, "board file"), str(path))


def write_board(path: Path | str, board: Board) -> None:
    write_json(path, board_to_dict(board))
