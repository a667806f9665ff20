"""The results panel's table of a row's targets (SPEC 13): the report's table, in the GUI.

Same rows as the PDF (:func:`lps_gui.report.pages.targets.target_table`):
views, ties, the stretch each target was seen over, pose sigma and its scale
term; hidden for a single-board session.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from PySide6.QtWidgets import QLabel, QVBoxLayout, QWidget

from lps_gui.gui.widgets import TextTable
from lps_gui.io.results.model import Results


class MountedTargetsView(QWidget):
    """A label and the table of targets; invisible until results with ``targets`` come."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.label = QLabel("Targets")
        self.label.setWordWrap(True)  # its sentence wraps: it used to widen the results dock to 740 px
        self.table = TextTable(numeric=range(1, 9))
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 4, 0, 0)
        lay.addWidget(self.label)
        lay.addWidget(self.table, 1)
        self.setVisible(False)

    def set_results(self, results: Results | Mapping[str, Any]) -> None:
        from lps_gui.report.pages.targets import target_table

        table = target_table(results)
        self.setVisible(table is not None)
        if table is None:
            return
        header, rows, _ = table
        self.table.set_rows([h.replace("\n", " ") for h in header], rows)
        self.label.setText(f"Targets: {len(rows)} mounted, pose in the world frame of {rows[0][0]} "
                           "(the deviation plot marks the stretch each was seen over)")
