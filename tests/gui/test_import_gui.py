"""File > Import images: the dialog gathers what `lps import` takes, the import runs as a job, and the new session
is opened for estimation; a bad folder is the same one-line error as on the command line."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.io.session import Session

pytestmark = pytest.mark.gui


def _folder(tmp_path: Path, names: list[str]) -> tuple[Path, Path]:
    photos = tmp_path / "photos"
    photos.mkdir()
    for i, name in enumerate(names):
        cv2.imwrite(str(photos / name), np.full((24, 32), 10 * i + 5, np.uint8))
    board = tmp_path / "board.json"
    board.write_text(json.dumps({"type": "chessboard", "inner_corners": [9, 6], "square_mm": 10.0}))
    return photos, board


def test_the_menu_imports_a_folder_and_opens_the_session(qtbot, window, tmp_path):
    photos, board = _folder(tmp_path, ["p_0.png", "p_0.5.png", "p_1.png", "p_0.75.png"])
    file_menu = window.menuBar().actions()[0].menu()
    assert "Import images…" in [a.text() for a in file_menu.actions()]
    dialog = window.import_dialog()
    dialog.accept()  # nothing filled in: the dialog says what is missing and stays open
    assert dialog.isVisible() and "Images: choose the folder" in dialog.message.text()
    dialog.images.set_text(str(photos))
    dialog.board.set_text(str(board))
    dialog.out.set_text(str(tmp_path / "session"))
    dialog.source.setCurrentIndex(dialog.source.findData("names"))
    dialog.pattern.setText("p_{mm}.png")
    dialog.accept()
    assert not dialog.isVisible()
    qtbot.waitUntil(lambda: window.estimation_panel.session.text() == str(tmp_path / "session"), timeout=20000)
    records = Session.open(tmp_path / "session").records()
    assert [(r.target_mm, r.direction, r.source) for r in records] == [
        (0.0, "+", "import"), (0.5, "+", "import"), (0.75, "+", "import"), (1.0, "+", "import")]
    assert window.last_error is None


def test_a_bad_folder_is_a_one_line_message(qtbot, window, tmp_path):
    photos, board = _folder(tmp_path, ["a.png", "b.png"])
    (photos / "notes.txt").write_text("x")
    dialog = window.import_dialog()
    dialog.images.set_text(str(photos))
    dialog.board.set_text(str(board))
    dialog.in_place.setChecked(True)
    assert not dialog.out.isEnabled()
    dialog.accept()
    qtbot.waitUntil(lambda: window.last_error is not None, timeout=20000)
    title, message = window.last_error
    assert "notes.txt: not an image file" in message and "\n" not in message
    assert not (photos / "session.json").exists()
