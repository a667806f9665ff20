"""Printable targets: the vector drawing is OpenCV's board, pages at true size, the list reads back."""
from __future__ import annotations

import numpy as np
import pytest
from pypdf import PdfReader

from lps_gui.camera.charuco import aruco_board
from lps_gui.cli import main
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.targets import Target
from lps_gui.io.jsonfile import read_json
from lps_gui.io.targets_file import targets_from_list
from lps_gui.report.pdf.targets import CAPTION_MM, MARGIN_MM, board_rectangles


@pytest.mark.parametrize("first", [0, 44])
def test_the_vector_drawing_is_the_board_opencv_detects(first):
    board = Board(6, 4, 10.0, type="charuco", marker_mm=7.0)
    target = Target("T", board, first)
    px_per_mm = 8
    w, h = (board.cols + 1) * 10 * px_per_mm, (board.rows + 1) * 10 * px_per_mm
    ours = np.full((h, w), 255, np.uint8)
    for x, y, rw, rh in board_rectangles(target):
        ours[round(y * px_per_mm): round((y + rh) * px_per_mm), round(x * px_per_mm): round((x + rw) * px_per_mm)] = 0
    theirs = aruco_board(board, first).generateImage((w, h), marginSize=0)
    assert np.mean(ours == theirs) > 0.995  # only cell edges rounded differently


def test_make_targets_writes_true_scale_pages_and_the_session_list(tmp_path, capsys):
    assert main(["make-targets", str(tmp_path / "row"), "--count", "3", "--inner-corners", "10x7",
                 "--square-mm", "30", "--marker-mm", "22"]) == 0
    pdf = PdfReader(str(tmp_path / "row" / "targets.pdf"))
    assert len(pdf.pages) == 3
    box = pdf.pages[1].mediabox
    to_mm = 25.4 / 72
    assert float(box.width) * to_mm == pytest.approx(11 * 30 + 2 * MARGIN_MM, abs=0.5)  # Qt rounds page sizes to points
    assert float(box.height) * to_mm == pytest.approx(8 * 30 + 2 * MARGIN_MM + CAPTION_MM, abs=0.5)
    text = " ".join(pdf.pages[1].extract_text().split())
    assert "target T1" in text and "ids 44-87" in text and "100 mm: print at 100 %" in text
    targets = targets_from_list(read_json(tmp_path / "row" / "targets.json", "targets")["targets"])
    assert [t.first_marker for t in targets] == [0, 44, 88]
    assert targets[0].board.marker_mm == 22.0
    assert "marker ids 0-131" in capsys.readouterr().out


@pytest.mark.parametrize("args,words", [
    (["--count", "0"], "at least 1 and at most 100"),
    (["--count", "6", "--dictionary", "DICT_4X4_50"], "DICT_4X4_50 has 50"),
    (["--square-mm", "-3"], "must be at least 1 and at most 10000"),
    (["--marker-mm", "40"], "marker_mm 40.0 must be smaller than its square_mm 30.0"),
])
def test_bad_target_options_are_one_line_errors(tmp_path, capsys, args, words):
    try:
        code = main(["make-targets", str(tmp_path / "t"), *args])
    except SystemExit as exc:  # argparse's own usage error
        code = exc.code
    assert code == 2
    assert not (tmp_path / "t" / "targets.pdf").exists()
    last = capsys.readouterr().err.strip().splitlines()[-1]  # argparse prints its usage above its one-line error
    assert words in last
