"""The light field tab (issue 38): a light-field folder's epipolar-plane images before and after rectification, and
the epipolar check's numbers, as the report's light-field page shows them. What it shows is the registry's
(:data:`lps_gui.report.registry.FOLDER_SECTIONS`, plain data); here only how it is drawn."""
from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtGui import QPixmap
from PySide6.QtWidgets import QLabel, QScrollArea, QVBoxLayout, QWidget

from lps_gui.report.pages.lightfield import EPI_FILES


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

    def load(self, folder: Path | str, section: str = "lightfield") -> None:
        """Show ``folder`` (written by `lps lightfield` or `lps demo --lightfield`): the registry's content of it,
        a one-line InputError otherwise."""
        from lps_gui.report.registry import folder_section

        folder = Path(folder)
        content = folder_section(section).content(folder)
        self.summary.setText("\n".join(content.lines))
        self._originals = [QPixmap(path) for path, _ in content.pictures]
        for pix, (caption, picture), (_, title) in zip(self._originals, self.pictures, content.pictures):
            caption.setText(title)
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
