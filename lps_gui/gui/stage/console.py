"""A raw console to the controller (G-code and ``$`` commands), with history, like UGS / CNCjs / bCNC offer.

Lines go through the :class:`StageController` (the one command thread) to
``stage.command(line)`` and the reply (the lines the controller printed, then
``ok`` or the one-line error) is appended. Only a stage that declares a
:class:`~lps_gui.hardware.capabilities.Console` has one; for any other the
console says so and stays disabled.
"""
from __future__ import annotations

from concurrent.futures import Future

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFont, QKeyEvent
from PySide6.QtWidgets import QHBoxLayout, QLineEdit, QPlainTextEdit, QPushButton, QVBoxLayout, QWidget

from lps_gui.gui.stage.controller import StageController
from lps_gui.gui.workers import one_line
from lps_gui.hardware.capabilities import Console

HISTORY_MAX = 200


class HistoryLineEdit(QLineEdit):
    """A line edit whose Up / Down keys walk through the lines entered before (shell style)."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.history: list[str] = []
        self._index = 0  # == len(history): the line being typed

    def remember(self, line: str) -> None:
        if line and (not self.history or self.history[-1] != line):
            self.history.append(line)
            del self.history[:-HISTORY_MAX]
        self._index = len(self.history)

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key.Key_Up, Qt.Key.Key_Down) and self.history:
            step = -1 if event.key() == Qt.Key.Key_Up else 1
            self._index = min(max(self._index + step, 0), len(self.history))
            self.setText(self.history[self._index] if self._index < len(self.history) else "")
            return
        super().keyPressEvent(event)


class StageConsole(QWidget):
    """Type a line, Enter sends it; the transcript shows what went out and what came back."""

    _reply = Signal(str)  # from the stage thread

    def __init__(self, controller: StageController, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.transcript = QPlainTextEdit()
        self.transcript.setReadOnly(True)
        self.transcript.setMaximumBlockCount(2000)
        mono = QFont()
        mono.setStyleHint(QFont.StyleHint.Monospace)
        mono.setFamily("monospace")
        self.transcript.setFont(mono)
        self.line = HistoryLineEdit()
        self.send_btn = QPushButton("Send")
        row = QHBoxLayout()
        row.addWidget(self.line, 1)
        row.addWidget(self.send_btn)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.transcript, 1)
        lay.addLayout(row)
        self.line.returnPressed.connect(self.send)
        self.send_btn.clicked.connect(self.send)
        self._reply.connect(self.transcript.appendPlainText)
        controller.connection_changed.connect(lambda _c, _d: self.update_enabled())
        self.update_enabled()

    def available(self) -> bool:
        stage = self.controller.stage
        return isinstance(stage, Console)

    def update_enabled(self) -> None:
        on = self.available()
        self.line.setEnabled(on)
        self.send_btn.setEnabled(on)
        stage = self.controller.stage
        self.line.setPlaceholderText(console_placeholder(stage is not None, stage.console_hint if isinstance(stage, Console) else ""))

    def send(self) -> Future | None:
        text = self.line.text().strip()
        if not text or not self.available():
            return None
        self.line.remember(text)
        self.line.clear()
        self.transcript.appendPlainText(f"> {text}")
        fut = self.controller.call(f"console {text}", "command", text)
        if fut is not None:
            fut.add_done_callback(self._answered)
        return fut

    def _answered(self, fut: Future) -> None:  # stage thread: only emit
        exc = fut.exception()
        if exc is not None:
            self._reply.emit(f"  {one_line(exc)}")
            return
        for ln in fut.result() or []:
            self._reply.emit(f"  {ln}")
        self._reply.emit("  ok")


def console_placeholder(connected: bool, hint: str) -> str:
    """What the command line says it takes: the connected stage's console ``hint`` ("" when it has none)."""
    if hint:
        return hint
    if connected:
        return "this stage has no G-code console"
    return "connect a stage with a console (a G-code controller) to send it commands"
