"""The digital readout: work, machine and offset of each axis from one status report, G54-G59, zero and return.

the WorkCoordinates capability's model: work = machine - offset of the selected system, so the
offset shown is machine - work of the same report (G54 -500 reads -500). The
value labels have a fixed size: a new text repaints them without re-laying
out the window (at the poll rate that starved the GUI thread during a
capture). Zero rewrites a stored offset, so it asks first, naming the system.
"""
from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFont
from PySide6.QtWidgets import (
    QComboBox,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QMessageBox,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from lps_gui.hardware.stage import AXES, WORK_SYSTEMS, StageStatus

STATE_COLORS = {"Idle": "#2a9d3c", "Run": "#1f5fa8", "Jog": "#1f5fa8", "Home": "#1f5fa8", "Hold": "#e07b00",
                "Alarm": "#d00000", "Door": "#d00000", "Disconnected": "#777777"}
WIDEST_MM = "-0000.000"  # a 10 m travel fits


class PositionReadout(QGroupBox):
    """Per axis: work (large), machine, offset, Zero, →0; the work system selector; state and feed."""

    system_chosen = Signal(str)  # G54..G59 picked by the operator
    zero_confirmed = Signal(str)  # axis: the operator confirmed zeroing it in the selected system
    to_zero_requested = Signal(str)  # axis: move it to its work zero

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__("Position", parent)
        grid = QGridLayout(self)
        grid.setHorizontalSpacing(6)
        big = QFont()
        big.setPointSize(14)
        big.setBold(True)
        big.setStyleHint(QFont.StyleHint.Monospace)
        self.readout: dict[str, QLabel] = {}
        self.machine: dict[str, QLabel] = {}
        self.offset: dict[str, QLabel] = {}
        self.zero_buttons: dict[str, QPushButton] = {}
        self.to_zero_buttons: dict[str, QPushButton] = {}
        self.axis_widgets: dict[str, list[QWidget]] = {}
        self.zero_box: QMessageBox | None = None
        self.work_system = QComboBox()
        for name in WORK_SYSTEMS:
            self.work_system.addItem(name, name)
        self.work_system.setToolTip("Work coordinate system (G54-G59) the readout, Go to and Zero refer to")
        self.work_system.activated.connect(lambda _i: self.system_chosen.emit(self.work_system.currentData()))
        grid.addWidget(self.work_system, 0, 1, alignment=Qt.AlignmentFlag.AlignRight)
        head = QLabel("Machine\nOffset")  # one column, the two numbers stacked: the readout fits a 1000 px screen's dock
        head.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        head.setToolTip("Machine: machine coordinates (the homed space), mm.\nOffset: work offset of the selected "
                        "system in mm: work = machine − offset")
        grid.addWidget(head, 0, 2, alignment=Qt.AlignmentFlag.AlignRight)
        for row, ax in enumerate(AXES, start=1):
            self._axis_row(grid, row, ax, big)
        self.state_label = fixed_label(self.font(), "Disconnected", Qt.AlignmentFlag.AlignCenter)
        self.state_label.setFixedSize(self.state_label.width() + 20, self.state_label.height() + 6)  # its padding
        self.feed_label = fixed_label(self.font(), "feed 00000 mm/min", Qt.AlignmentFlag.AlignLeft)
        self.feed_label.setText("feed 0 mm/min")
        state_row = QHBoxLayout()
        state_row.addWidget(self.state_label)
        state_row.addWidget(self.feed_label)
        state_row.addStretch(1)
        grid.addLayout(state_row, len(AXES) + 1, 0, 1, 5)
        self.show_state("Disconnected")

    def _axis_row(self, grid: QGridLayout, row: int, ax: str, big: QFont) -> None:
        name = QLabel(ax)
        name.setFont(big)
        val = fixed_label(big, WIDEST_MM)
        val.setToolTip(f"{ax} in work coordinates of the selected system, mm")
        mach = fixed_label(self.font(), WIDEST_MM)
        off = fixed_label(self.font(), WIDEST_MM)
        for w in (mach, off):
            w.setStyleSheet("QLabel { color: #555555; }")
        zero = QPushButton("Zero")
        zero.setToolTip(f"Make {ax} read 0 here in the selected work system (asks first)")
        zero.clicked.connect(lambda _=False, a=ax: self.ask_zero(a))
        home = QPushButton("→0")
        home.setToolTip(f"Move {ax} to its work zero at the jog feed")
        home.clicked.connect(lambda _=False, a=ax: self.to_zero_requested.emit(a))
        for b in (zero, home):
            b.setFixedWidth(b.fontMetrics().horizontalAdvance("Zero") + 14)
        both = QVBoxLayout()  # machine above offset, beside the large work value
        both.setSpacing(0)
        both.addWidget(mach)
        both.addWidget(off)
        grid.addWidget(name, row, 0)
        grid.addWidget(val, row, 1)
        grid.addLayout(both, row, 2)
        grid.addWidget(zero, row, 3)
        grid.addWidget(home, row, 4)
        self.readout[ax], self.machine[ax], self.offset[ax] = val, mach, off
        self.zero_buttons[ax], self.to_zero_buttons[ax] = zero, home
        self.axis_widgets[ax] = [name, val, mach, off, zero, home]

    # ------------------------------------------------------------------ showing
    def show_status(self, st: StageStatus) -> None:
        """Work, machine and offset (machine - work) of this one report, state and feed."""
        for ax, m, w in zip(AXES, st.machine_mm, st.work_mm):
            self.readout[ax].setText(f"{w:10.3f}")
            self.machine[ax].setText(f"{m:.3f}")
            self.offset[ax].setText(f"{m - w:.3f}")
        self.show_state(st.state)
        self.feed_label.setText(f"feed {st.feed_mm_min:.0f} mm/min")

    def clear(self) -> None:
        self.show_state("Disconnected")
        for labels in (self.readout, self.machine, self.offset):
            for v in labels.values():
                v.setText("---")

    def show_state(self, state: str) -> None:
        color = STATE_COLORS.get(state, "#555555")
        self.state_label.setText(state)
        self.state_label.setStyleSheet(
            f"QLabel {{ background: {color}; color: white; border-radius: 4px; padding: 4px 8px; font-weight: bold; }}")

    def show_system(self, name: str) -> None:
        i = self.work_system.findData(name)
        if i >= 0:
            self.work_system.setCurrentIndex(i)

    def set_offsets_enabled(self, on: bool) -> None:
        """Zero and the selector only for a stage with work coordinate systems."""
        for b in self.zero_buttons.values():
            b.setEnabled(on)
        self.work_system.setEnabled(on)

    def ask_zero(self, axis: str) -> None:
        """Confirm, naming the system, then :attr:`zero_confirmed` (it rewrites a stored offset)."""
        system = self.work_system.currentData()
        box = QMessageBox(QMessageBox.Icon.Question, f"Zero {axis} in {system}?",
                          f"Make {axis} read 0.000 mm here in {system}?\n"
                          f"This changes the {system} offset stored in the controller; the other systems "
                          "and the machine position stay as they are.",
                          QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.Cancel, self)
        box.setDefaultButton(QMessageBox.StandardButton.Cancel)
        box.button(QMessageBox.StandardButton.Yes).setText(f"Zero {axis} in {system}")
        box.finished.connect(lambda r: self.zero_confirmed.emit(axis) if r == QMessageBox.StandardButton.Yes else None)
        box.open()
        self.zero_box = box


def fixed_label(font: QFont, widest: str, align: Qt.AlignmentFlag = Qt.AlignmentFlag.AlignRight) -> QLabel:
    """A label sized once for ``widest``: new text repaints it without a window re-layout."""
    label = QLabel("---")
    label.setFont(font)
    label.setAlignment(align | Qt.AlignmentFlag.AlignVCenter)
    fm = label.fontMetrics()
    label.setFixedSize(fm.horizontalAdvance(widest) + 8, fm.height() + 4)
    return label
