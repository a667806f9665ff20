"""Small widgets the panels share: a path picker and a parameter table."""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Sequence

from PySide6.QtCore import QAbstractTableModel, QModelIndex, Qt, Signal
from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QHeaderView,
    QLayout,
    QLineEdit,
    QPushButton,
    QTableView,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
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

    def __init__(self, headers: Sequence[str], numeric: Sequence[int] = (1, 2), parent: QWidget | None = None,
                 stretch: int | None = None) -> None:
        super().__init__(0, len(headers), parent)
        self.numeric = set(numeric)  # right-aligned columns
        self.stretch = stretch  # kept for callers; every column now gives up width alike (fit_columns)
        self.setTextElideMode(Qt.TextElideMode.ElideRight)
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
                    item.setToolTip(str(text))  # an elided cell shows its whole text on hover
                    if c in self.numeric:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                    self.setItem(r, c, item)
            self.resizeColumnsToContents()
            self._widths = [hh.sectionSize(c) for c in range(self.columnCount())]
            self.fit_columns()
            hh.setStretchLastSection(True)
        finally:
            self.setUpdatesEnabled(True)

    def fit_columns(self) -> None:
        """Columns as wide as their text when the table has the room; in a narrow table each gives up the same
        share of what it has beyond its header (text elided, whole in the tooltip), never less than its header.
        A stretched column used to be squeezed to ~25 px beside wide numbers, its header unreadable."""
        widths = getattr(self, "_widths", None)
        if not widths or len(widths) != self.columnCount():
            return
        hh = self.horizontalHeader()
        mins = [min(w, hh.sectionSizeFromContents(c).width()) for c, w in enumerate(widths)]
        room = self.viewport().width()
        spare = sum(widths) - sum(mins)
        f = 1.0 if sum(widths) <= room or spare <= 0 else max(0.0, (room - sum(mins)) / spare)
        for c, (w, m) in enumerate(zip(widths, mins)):
            hh.resizeSection(c, int(m + (w - m) * f))

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        super().resizeEvent(event)
        self.fit_columns()

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
    form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)  # narrow dock: the field goes under its label
    for label, widget in rows:
        form.addRow(label, widget)


class TextTableModel(QAbstractTableModel):
    """Rows of text served on demand: a long table costs nothing until it is scrolled to."""

    def __init__(self, numeric: Sequence[int] = ()) -> None:
        super().__init__()
        self.header: list[str] = []
        self.rows: list[Sequence[str]] = []
        self.colors: list[str | None] = []
        self.numeric = set(numeric)

    def set_rows(self, header: Sequence[str], rows: Sequence[Sequence[str]],
                 colors: Sequence[str | None] | None = None) -> None:
        """``colors``: a text colour per row (None: the default), e.g. grey for what is not resolved."""
        self.beginResetModel()
        self.header, self.rows = list(header), list(rows)
        self.colors = list(colors) if colors is not None else []
        self.endResetModel()

    def rowCount(self, parent: QModelIndex = QModelIndex()) -> int:  # noqa: B008 (Qt signature)
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent: QModelIndex = QModelIndex()) -> int:  # noqa: B008
        return 0 if parent.isValid() else len(self.header)

    def data(self, index: QModelIndex, role: int = Qt.ItemDataRole.DisplayRole) -> object:
        if role == Qt.ItemDataRole.DisplayRole:
            return str(self.rows[index.row()][index.column()])
        if role == Qt.ItemDataRole.TextAlignmentRole and index.column() in self.numeric:
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        if role == Qt.ItemDataRole.ForegroundRole and index.row() < len(self.colors) and self.colors[index.row()]:
            return QColor(self.colors[index.row()])
        return None

    def headerData(self, section: int, orientation: Qt.Orientation, role: int = Qt.ItemDataRole.DisplayRole) -> object:
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return self.header[section] if section < len(self.header) else None
        return None


class TextTable(QTableView):
    """A read-only view of a :class:`TextTableModel` (the per-position table of a long session)."""

    def __init__(self, numeric: Sequence[int] = (), parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model_ = TextTableModel(numeric)
        self.setModel(self.model_)
        self.verticalHeader().setVisible(False)
        self.setAlternatingRowColors(True)
        self.horizontalHeader().setStretchLastSection(True)
        self.horizontalHeader().setResizeContentsPrecision(40)  # size columns from 40 rows, not all

    def set_rows(self, header: Sequence[str], rows: Sequence[Sequence[str]],
                 colors: Sequence[str | None] | None = None) -> None:
        self.model_.set_rows(header, rows, colors)
        for c in range(len(header)):  # width from the header and the first rows only: cheap for any length
            self.resizeColumnToContents(c)

    def rowCount(self) -> int:
        return self.model_.rowCount()


def stack(owner: QWidget, items: Sequence[QWidget | QLayout | tuple[QWidget, int]], margin: int = 6) -> QVBoxLayout:
    """Lay ``items`` out top to bottom in ``owner``; a (widget, stretch) pair takes the spare height."""
    lay = QVBoxLayout(owner)
    lay.setContentsMargins(margin, margin, margin, margin)
    for item in items:
        if isinstance(item, tuple):
            lay.addWidget(*item)
        elif isinstance(item, QLayout):
            lay.addLayout(item)
        else:
            lay.addWidget(item)
    return lay
