"""File > Import images: the fields of `lps import` in a dialog (SPEC 16).

The dialog only gathers what :func:`lps_gui.capture.import_images.import_images`
takes and reads the board and intrinsics files (so a wrong file is refused
while the dialog is still open); the main window runs the import as a job.
"""
from __future__ import annotations

from typing import Any, Callable

from PySide6.QtWidgets import (
    QButtonGroup,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QGroupBox,
    QLabel,
    QLineEdit,
    QRadioButton,
    QSpinBox,
    QStackedWidget,
    QVBoxLayout,
    QWidget,
)

from lps_gui.errors import InputError
from lps_gui.gui.widgets import PathPicker, add_rows, double_spin

POSITION_SOURCES = (("step", "A step from a start (images in name order)"), ("names", "Numbers in the file names"),
                    ("csv", "A CSV of file,target[,direction,run]"))
DEFAULT_PATTERN = "pos_{mm}.png"


class ImportDialog(QDialog):
    """Images folder, where the session goes, how the positions are given, board and intrinsics."""

    def __init__(self, start_dir: Callable[[], str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Import images")
        self.images = PathPicker("folder of the images (never modified)", start_dir=start_dir)
        self.copy = QRadioButton("Copy the images into a new session folder")
        self.in_place = QRadioButton("Write the session into the image folder (no copy)")
        self.copy.setChecked(True)
        group = QButtonGroup(self)
        group.addButton(self.copy)
        group.addButton(self.in_place)
        self.out = PathPicker("new session folder", start_dir=start_dir)
        self.in_place.toggled.connect(lambda on: self.out.setEnabled(not on))
        self.source = QComboBox()
        for key, text in POSITION_SOURCES:
            self.source.addItem(text, key)
        self.step = double_spin(1e-4, 1e6, 1.0, 4, " mm")
        self.start = double_spin(-1e6, 1e6, 0.0, 4, " mm")
        self.directions = QComboBox()
        for key, text in (("+", "forward"), ("-", "backward"), ("both", "forward then backward")):
            self.directions.addItem(text, key)
        self.runs = QSpinBox()
        self.runs.setRange(1, 1000)
        self.pattern = QLineEdit(DEFAULT_PATTERN)
        self.pattern.setToolTip("{mm} the position; also {index}, {run}, {dir} (+, -, fwd, bwd) and * for any text")
        self.csv = PathPicker("positions CSV", folder=False, filter="CSV (*.csv *.txt)", start_dir=start_dir)
        self.pages = QStackedWidget()
        for rows in ((("Step", self.step), ("Start", self.start), ("Passes", self.directions), ("Runs", self.runs)),
                     (("Pattern", self.pattern),), (("File", self.csv),)):
            page = QWidget()
            add_rows(QFormLayout(page), rows)
            self.pages.addWidget(page)
        self.source.currentIndexChanged.connect(self.pages.setCurrentIndex)
        self.board = PathPicker("board.json", folder=False, filter="Board (*.json)", start_dir=start_dir)
        self.intrinsics = PathPicker("intrinsics (optional)", folder=False, filter="Intrinsics (*.json *.yaml *.yml *.xml)",
                                     start_dir=start_dir)
        self.message = QLabel()
        self.message.setWordWrap(True)
        self.message.setStyleSheet("color: #b00020")
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        self.ok_button = buttons.button(QDialogButtonBox.StandardButton.Ok)
        self.ok_button.setText("Import")
        positions = QGroupBox("Positions")
        lay = QVBoxLayout(positions)
        lay.addWidget(self.source)
        lay.addWidget(self.pages)
        form = QFormLayout()
        add_rows(form, (("Images", self.images), ("", self.copy), ("Session", self.out), ("", self.in_place)))
        set_up = QFormLayout()
        add_rows(set_up, (("Board", self.board), ("Intrinsics", self.intrinsics)))
        outer = QVBoxLayout(self)
        for item in (form, positions, set_up):
            outer.addLayout(item) if isinstance(item, QFormLayout) else outer.addWidget(item)
        outer.addWidget(self.message)
        outer.addWidget(buttons)
        self.request: dict[str, Any] | None = None

    def accept(self) -> None:
        """Close only when the fields make an import; otherwise say what is missing and stay open."""
        try:
            self.request = self.import_arguments()
        except InputError as exc:
            self.message.setText(str(exc))
            return
        super().accept()

    def import_arguments(self) -> dict[str, Any]:
        """Keyword arguments of :func:`~lps_gui.capture.import_images.import_images` (board and intrinsics read)."""
        from lps_gui.capture.import_images import Positions
        from lps_gui.io.board_file import read_board
        from lps_gui.io.intrinsics_file import read_intrinsics

        images, board = self.images.path(), self.board.path()
        if images is None:
            raise InputError("Images: choose the folder of the images")
        if board is None:
            raise InputError("Board: choose the board.json of the chessboard in the images")
        in_place = self.in_place.isChecked()
        if not in_place and self.out.path() is None:
            raise InputError("Session: choose a new folder for the session, or write it into the image folder")
        kind = self.source.currentData()
        if kind == "step":
            positions = Positions(step_mm=self.step.value(), start_mm=self.start.value(),
                                  directions=self.directions.currentData(), runs=self.runs.value())
        elif kind == "names":
            positions = Positions(names=self.pattern.text().strip())
        else:
            if self.csv.path() is None:
                raise InputError("File: choose the CSV of file,target[,direction,run]")
            positions = Positions(csv=self.csv.path())
        intrinsics_path = self.intrinsics.path()
        return {"images_dir": images, "out": None if in_place else self.out.path(), "board": read_board(board),
                "positions": positions, "intrinsics": read_intrinsics(intrinsics_path) if intrinsics_path else None,
                "in_place": in_place,
                "extra": {"intrinsics_source": str(intrinsics_path)} if intrinsics_path else None}

