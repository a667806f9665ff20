"""The light field tab (issue 38): a light-field folder's epipolar-plane images before and after rectification, and
the epipolar check's numbers, as the report's light-field page shows them."""
from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtGui import QPixmap
from PySide6.QtWidgets import QLabel, QScrollArea, QVBoxLayout, QWidget

from lps_gui.errors import InputError

LIGHTFIELD_FILE = "lightfield.json"
EPI_FILES = (("epi_before.png", "Epipolar-plane image before rectification"),
             ("epi_after.png", "After rectification: every scene point a straight line, rows level"))


class LightFieldPage(QScrollArea):
    """One light field's EPIs and numbers; scrolls when the dock is short."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWidgetResizable(True)
        body = QWidget()
        self._layout = QVBoxLayout(body)
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self._layout.addWidget(self.summary)
        self.pictures: list[tuple[QLabel, QLabel]] = []
        for _, title in EPI_FILES:
            caption, picture = QLabel(title), QLabel()
            caption.setWordWrap(True)
            picture.setAlignment(Qt.AlignmentFlag.AlignLeft)
            self._layout.addWidget(caption)
            self._layout.addWidget(picture)
            self.pictures.append((caption, picture))
        self._layout.addStretch(1)
        self.setWidget(body)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)  # pictures follow the width
        self.folder: Path | None = None
        self._originals: list[QPixmap] = []

    def load(self, folder: Path | str) -> None:
        """Show ``folder`` (written by `lps lightfield` or `lps demo --lightfield`); a one-line InputError otherwise."""
        from lps_gui.io.jsonfile import read_json
        from lps_gui.pipeline.lightfield import check_lines

        folder = Path(folder)
        if not (folder / LIGHTFIELD_FILE).is_file():
            raise InputError(f"{folder}: no {LIGHTFIELD_FILE} here; choose a folder written by `lps lightfield`")
        doc = read_json(folder / LIGHTFIELD_FILE, "light field file")
        uniform = doc.get("uniform") or {}
        lines = [f"{len(doc.get('views') or [])} views on {' and '.join(doc.get('axes') or ['X'])}",
                 *check_lines(doc.get("check")),
                 "HCI layout written" if uniform.get("hci") else (uniform.get("refusal") or "HCI layout not written")]
        self.summary.setText("\n".join(lines))
        self._originals = [QPixmap(str(folder / name)) for name, _ in EPI_FILES]
        for pix, (caption, picture) in zip(self._originals, self.pictures):
            for w in (caption, picture):
                w.setVisible(not pix.isNull())
        self.folder = folder
        self._fit_pictures()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        super().resizeEvent(event)
        self._fit_pictures()

    def _fit_pictures(self) -> None:
        """Each EPI scaled to the visible width (never enlarged), so the numbers above it wrap instead of clipping."""
        width = max(self.viewport().width() - 24, 50)
        for pix, (_, picture) in zip(self._originals, self.pictures):
            if not pix.isNull():
                picture.setPixmap(pix if pix.width() <= width else
                                  pix.scaledToWidth(width, Qt.TransformationMode.SmoothTransformation))
