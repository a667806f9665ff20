"""The capture panel's targets (SPEC 13): a row or constellation of ChArUco targets instead of the one board.

The operator adds targets in groups (count, inner corners, square, marker,
dictionary): each new target's first marker is the next free id of its
dictionary, so the ranges stay disjoint whatever is added or removed; or loads
the ``targets.json`` that ``lps make-targets`` wrote for the prints. The list
goes into session.json ``targets`` (:func:`lps_gui.io.targets_file.targets_to_list`).
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

from PySide6.QtCore import QSettings, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.targets import Target, check_targets
from lps_gui.errors import InputError
from lps_gui.gui.widgets import double_spin
from lps_gui.gui.workers import one_line

DICTIONARIES = ("DICT_5X5_1000", "DICT_4X4_1000", "DICT_6X6_1000", "DICT_7X7_1000", "DICT_ARUCO_ORIGINAL")
COLUMNS = ("id", "board", "dictionary", "marker ids")
SETTINGS_KEY = "capture/targets"


def next_first_marker(targets: list[Target], dictionary: str) -> int:
    """The first marker id after every range already used in ``dictionary``."""
    return max((t.marker_range.stop for t in targets if (t.board.dictionary or "") == dictionary), default=0)


def next_id(targets: list[Target]) -> str:
    """T<n> with the smallest n not taken."""
    taken = {t.id for t in targets}
    return next(f"T{n}" for n in range(len(targets) + 1) if f"T{n}" not in taken)


def add_targets(targets: list[Target], count: int, board: Board) -> list[Target]:
    """``targets`` and ``count`` more of ``board``, each on the next free marker range of its dictionary."""
    out = list(targets)
    for _ in range(count):
        out.append(Target(next_id(out), board, next_first_marker(out, board.dictionary or "")))
    check_targets(out)
    return out


def read_targets_json(path: Path) -> list[Target]:
    """The list of a ``targets.json`` (``{"targets": [...]}`` as make-targets writes) or of a session.json."""
    from lps_gui.io.jsonfile import read_json
    from lps_gui.io.targets_file import dictionary_sizes, targets_from_list

    data = read_json(path, "targets file")
    items = data.get("targets") if isinstance(data, dict) else data
    if items is None:
        raise InputError(f"{path}: has no \"targets\" list; load the targets.json that lps make-targets wrote")
    targets = targets_from_list(items, f"{path} targets")
    check_targets(targets, dictionary_sizes(targets))
    return targets


class TargetsEditor(QGroupBox):
    """Checked: the session measures against these targets; unchecked: against the one board."""

    changed = Signal()

    def __init__(self, start_dir: Callable[[], str] | None = None, parent: QWidget | None = None) -> None:
        super().__init__("Targets (a row, not one board)", parent)
        self.setCheckable(True)
        self.setChecked(False)
        self.setToolTip("Several ChArUco targets fixed along the travel, with their own marker ids "
                        "(docs/targets.md); lps plan-rig --travel proposes a layout")
        self.start_dir = start_dir or (lambda: "")
        self._targets: list[Target] = []
        self.count = QSpinBox()
        self.count.setRange(1, 100)
        self.count.setValue(6)
        self.cols, self.rows = QSpinBox(), QSpinBox()
        for spin, value in ((self.cols, 10), (self.rows, 7)):
            spin.setRange(2, 100)
            spin.setValue(value)
        corners = QHBoxLayout()
        corners.addWidget(self.cols)
        corners.addWidget(QLabel("x"))
        corners.addWidget(self.rows)
        self.square_mm = double_spin(0.1, 1000.0, 30.0, 3, " mm")
        self.marker_mm = double_spin(0.1, 1000.0, 22.0, 3, " mm")
        self.dictionary = QComboBox()
        self.dictionary.addItems(DICTIONARIES)
        self.add_btn = QPushButton("Add")
        self.add_btn.setToolTip("Add this many targets; each starts at the next free marker id of its dictionary")
        self.remove_btn = QPushButton("Remove")
        self.clear_btn = QPushButton("Clear")
        self.load_btn = QPushButton("Load targets.json…")
        self.load_btn.setToolTip("The targets.json that lps make-targets wrote beside targets.pdf")
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setMinimumHeight(110)
        self.status = QLabel("")
        self.status.setWordWrap(True)

        form = QFormLayout()
        form.addRow("Count", self.count)
        form.addRow("Inner corners", corners)
        form.addRow("Square", self.square_mm)
        form.addRow("Marker", self.marker_mm)
        form.addRow("Dictionary", self.dictionary)
        buttons = QHBoxLayout()
        for b in (self.add_btn, self.remove_btn, self.clear_btn, self.load_btn):
            buttons.addWidget(b)
        self.body = QWidget()  # hidden while unchecked: the one board needs none of this room
        body = QVBoxLayout(self.body)
        body.setContentsMargins(0, 0, 0, 0)
        body.addLayout(form)
        body.addLayout(buttons)
        body.addWidget(self.table, 1)
        body.addWidget(self.status)
        lay = QVBoxLayout(self)
        lay.addWidget(self.body)
        self.body.setVisible(False)
        self._fold(False)
        self.add_btn.clicked.connect(self.add)
        self.remove_btn.clicked.connect(self.remove_selected)
        self.clear_btn.clicked.connect(lambda: self.set_targets([]))
        self.load_btn.clicked.connect(self.load_dialog)
        self.toggled.connect(self.body.setVisible)
        self.toggled.connect(self._fold)
        self.toggled.connect(lambda _on: self.changed.emit())
        self._show()

    def _fold(self, on: bool) -> None:
        """Unchecked: the title alone (flat, no margins), not an empty frame under it."""
        self.setFlat(not on)
        margin = 9 if on else 0
        self.layout().setContentsMargins(margin, margin if on else 0, margin, margin)

    # ------------------------------------------------------------------ the list
    def targets(self) -> list[Target] | None:
        """The targets for session.json; None when unchecked (the one board). Checked but empty is an error."""
        if not self.isChecked():
            return None
        if not self._targets:
            raise InputError("targets: the list is empty; add targets or load a targets.json, or uncheck Targets")
        return list(self._targets)

    def set_targets(self, targets: list[Target]) -> None:
        self._targets = list(targets)
        self._show()
        self.changed.emit()

    def add(self) -> None:
        try:
            board = Board(self.cols.value(), self.rows.value(), self.square_mm.value(), type="charuco",
                          marker_mm=self.marker_mm.value(), dictionary=self.dictionary.currentText())
            self.set_targets(add_targets(self._targets, self.count.value(), board))
        except InputError as exc:
            self._error(exc)

    def remove_selected(self) -> None:
        rows = {i.row() for i in self.table.selectedIndexes()}
        self.set_targets([t for j, t in enumerate(self._targets) if j not in rows])

    def load_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Load targets", self.start_dir(), "Targets (*.json);;All files (*)")
        if path:
            self.load(Path(path))

    def load(self, path: Path) -> None:
        try:
            self.set_targets(read_targets_json(path))
            self.setChecked(True)
        except InputError as exc:
            self._error(exc)

    # ------------------------------------------------------------------ showing
    def _show(self) -> None:
        self.table.setRowCount(len(self._targets))
        for j, t in enumerate(self._targets):
            b = t.board
            marker = f", marker {b.marker_mm:g}" if b.marker_mm else ""
            cells = (t.id, f"{b.cols}x{b.rows}, {b.square_mm:g} mm{marker}", (b.dictionary or "").removeprefix("DICT_"),
                     f"{t.marker_range.start}\u2013{t.marker_range.stop - 1}")
            for c, text in enumerate(cells):
                self.table.setItem(j, c, QTableWidgetItem(text))
        self.table.resizeColumnsToContents()
        if self._targets:
            width = sum(t.board.size_mm[0] for t in self._targets)
            self.status.setText(f"{len(self._targets)} targets, {width:.0f} mm of boards side by side; "
                                "written to session.json targets")
        else:
            self.status.setText("no targets yet: add some or load the targets.json of lps make-targets")

    def _error(self, exc: Exception) -> None:
        self.status.setText(f"<span style='color:#b00020'>{one_line(exc)}</span>")

    # ------------------------------------------------------------------ settings
    def save(self, s: QSettings) -> None:
        from lps_gui.io.targets_file import targets_to_list

        s.setValue(SETTINGS_KEY, json.dumps({"on": self.isChecked(), "targets": targets_to_list(self._targets)}))

    def restore(self, s: QSettings) -> None:
        from lps_gui.io.targets_file import targets_from_list

        try:
            saved: Any = json.loads(str(s.value(SETTINGS_KEY) or "{}"))
            self.set_targets(targets_from_list(saved.get("targets") or [], "saved targets") if saved.get("targets") else [])
            self.setChecked(bool(saved.get("on")) and bool(self._targets))
        except (InputError, ValueError, AttributeError):
            self.set_targets([])  # settings of an older version: start with none
