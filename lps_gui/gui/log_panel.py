"""The log panel: Python logging shown in a read-only text view.

Worker threads log freely; a handler turns each record into a queued Qt
signal so only the GUI thread appends text.
"""
from __future__ import annotations

import logging

from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QFont, QFontDatabase
from PySide6.QtWidgets import QHBoxLayout, QPlainTextEdit, QPushButton, QVBoxLayout, QWidget

MAX_LINES = 5000


class _Bridge(QObject):
    line = Signal(str, int)


class QtLogHandler(logging.Handler):
    """A logging handler that forwards formatted records through a Qt signal."""

    def __init__(self) -> None:
        super().__init__()
        self.bridge = _Bridge()
        self.setFormatter(logging.Formatter("%(asctime)s %(levelname)-7s %(message)s", "%H:%M:%S"))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.bridge.line.emit(self.format(record), record.levelno)
        except RuntimeError:  # the panel is gone while a worker still logs
            pass


class LogPanel(QWidget):
    """Read-only log with a clear button; tracebacks land here, message boxes show one line."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.view = QPlainTextEdit(self)
        self.view.setReadOnly(True)
        self.view.setMaximumBlockCount(MAX_LINES)
        font: QFont = QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont)
        self.view.setFont(font)
        clear = QPushButton("Clear", self)
        clear.clicked.connect(self.view.clear)
        row = QHBoxLayout()
        row.addStretch(1)
        row.addWidget(clear)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(self.view)
        lay.addLayout(row)
        self.handler = QtLogHandler()
        self.handler.bridge.line.connect(self.append)
        self.handler.setLevel(logging.INFO)

    def attach(self, logger: logging.Logger | None = None) -> None:
        (logger or logging.getLogger("lps_gui")).addHandler(self.handler)

    def detach(self, logger: logging.Logger | None = None) -> None:
        (logger or logging.getLogger("lps_gui")).removeHandler(self.handler)

    def append(self, text: str, level: int = logging.INFO) -> None:
        """Add a line; the view follows the newest line unless the reader scrolled up to read an older one."""
        bar = self.view.verticalScrollBar()
        following = bar.value() >= bar.maximum() - 2
        if level >= logging.ERROR:
            text = f"<span style='color:#b00020'>{_escape(text)}</span>"
            self.view.appendHtml(text)
        elif level >= logging.WARNING:
            self.view.appendHtml(f"<span style='color:#a15c00'>{_escape(text)}</span>")
        else:
            self.view.appendPlainText(text)
        if following:
            bar.setValue(bar.maximum())

    def text(self) -> str:
        return self.view.toPlainText()


def _escape(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("\n", "<br>")
