"""Small widgets the panels share: a path picker and a parameter table."""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QDoubleSpinBox, QFileDialog, QFormLayout, QHBoxLayout, QHeaderView, QLineEdit, QPushButton, QTableWidget, QTableWidgetItem, QWidget,
)


class PathPicker(QWidget):
    """A line edit with a Browse button; ``folder`` picks a directory, else a file."""

    changed = Signal(str)

    def __init__(self, placeholder: str, folder: bool = True, filter: str = "", start_dir: Callable[[], str] | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.folder = folder
        self.filter = filter
        self.start_dir = start_dir or (lambda: "")
        self.edit = QLineEdit()
        self.edit.setPlaceholderText(placeholder)
        self.edit.setClearButtonEnabled(True)
        self.browse = QPushButton("Browse…")
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.edit, 1)
        lay.addWidget(self.browse)
        self.browse.clicked.connect(self.pick)
        self.edit.editingFinished.connect(lambda: self.changed.emit(self.text()))

    def pick(self) -> None:
        start = self.text() or self.start_dir()
        if self.folder:
            path = QFileDialog.getExistingDirectory(self, "Choose a folder", start)
        else:
            path, _ = QFileDialog.getOpenFileName(self, "Choose a file", start, self.filter)
        if path:
            self.set_text(path)

    def text(self) -> str:
        return self.edit.text().strip()

    def path(self) -> Path | None:
        t = self.text()
        return Path(t) if t else None

    def set_text(self, text: str) -> None:
        self.edit.setText(str(text))
        self.changed.emit(self.text())


class ValueTable(QTableWidget):
    """A read-only table of rows of text, sized to its contents."""

    def __init__(self, headers: Sequence[str], numeric: Sequence[int] = (1, 2), parent: QWidget | None = None) -> None:
        super().__init__(0, len(headers), parent)
        self.numeric = set(numeric)  # right-aligned columns
        self.setHorizontalHeaderLabels(list(headers))
        self.verticalHeader().setVisible(False)
        self.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.setAlternatingRowColors(True)
        hh = self.horizontalHeader()
        hh.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        hh.setStretchLastSection(True)

    def set_rows(self, rows: Sequence[Sequence[str]]) -> None:
        """Replace the contents; columns are sized once at the end (per-cell sizing is slow)."""
        hh = self.horizontalHeader()
        hh.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        self.setUpdatesEnabled(False)
        try:
            self.setRowCount(len(rows))
            for r, row in enumerate(rows):
                for c, text in enumerate(row):
                    item = QTableWidgetItem(str(text))
                    if c in self.numeric:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                    self.setItem(r, c, item)
            self.resizeColumnsToContents()
            hh.setStretchLastSection(True)
        finally:
            self.setUpdatesEnabled(True)

    def cell(self, row: int, col: int) -> str:
        item = self.item(row, col)
        return item.text() if item else ""


def fmt(value: object, digits: int = 4) -> str:
    """A number for a table: significant digits, '—' when absent."""
    if value is None:
        return "—"
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(value)
    if v != v:
        return "—"
    if v.is_integer() and abs(v) < 1e9:
        return str(int(v))
    return f"{v:.{digits}g}"


def double_spin(lo: float, hi: float, value: float, decimals: int, suffix: str) -> QDoubleSpinBox:
    """A spin box for a physical value; the unit is part of the suffix."""
    s = QDoubleSpinBox()
    s.setRange(lo, hi)
    s.setDecimals(decimals)
    s.setValue(value)
    s.setSuffix(suffix)
    return s


def add_rows(form: QFormLayout, rows: Sequence[tuple[str, QWidget]]) -> None:
    """Fill a form layout with (label, widget) rows."""
    for label, widget in rows:
        form.addRow(label, widget)
