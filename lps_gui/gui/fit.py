"""Keep the window on the screen: panels that scroll, no wheel edits on unfocused fields, geometry clamped.

A dock's minimum height is its panel's; a panel that grows (a section
unfolded, the planar editor shown) used to push the whole window past the
screen, Start and the status bar with it. Inside a scroll area a panel can
grow without the window. Its width is capped too (:data:`DOCK_MIN_WIDTH`):
a panel wider than that scrolls sideways inside its dock, so the docks side by
side fit a 1000 px screen (they used to add up to 1179 px). A wheel turned over a field the operator did not
click used to change it (the plan Pattern while scrolling the panel): fields
take the wheel only once focused, otherwise it scrolls the panel.
"""
from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, QRect, Qt
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QAbstractButton, QAbstractSpinBox, QComboBox, QFrame, QScrollArea, QWidget

DOCK_MIN_WIDTH = 260  # px: the narrowest a scrolled panel's dock goes; three docks side by side fit 1000 px


def scrolled(panel: QWidget, min_width: int = DOCK_MIN_WIDTH) -> QScrollArea:
    """``panel`` in a frameless scroll area that follows the dock's width; it scrolls down, and sideways only
    when the dock is narrower than the panel can go (never below ``min_width``)."""
    area = QScrollArea()
    area.setWidgetResizable(True)
    area.setFrameShape(QFrame.Shape.NoFrame)
    area.setWidget(panel)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAsNeeded)
    bar = area.verticalScrollBar().sizeHint().width()
    area.setMinimumWidth(min(panel.minimumSizeHint().width() + bar, min_width))
    area.setObjectName(f"scroll_{panel.objectName() or type(panel).__name__}")
    return area


def compact_buttons(*buttons: QAbstractButton, padding: int = 16) -> None:
    """Buttons as narrow as their text (plus ``padding`` px), not the style's 80 px minimum: a row of three or
    four then fits a 1000 px screen's dock without scrolling sideways."""
    for b in buttons:
        b.setMinimumWidth(b.fontMetrics().horizontalAdvance(b.text().replace("&&", "&")) + padding)


class _WheelGuard(QObject):
    """Event filter: a wheel over an unfocused field goes on to the scroll area under it."""

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Wheel and isinstance(obj, QWidget) and not obj.hasFocus():
            event.ignore()  # ignored and filtered: Qt hands the wheel to the parents (the scroll area)
            return True
        return False


_GUARD = _WheelGuard()


def guard_wheel(root: QWidget) -> None:
    """Spin boxes and combo boxes under ``root``: focus by click or Tab only, the wheel only when focused."""
    for w in root.findChildren(QAbstractSpinBox) + root.findChildren(QComboBox):
        if w.property("_wheel_guarded"):
            continue
        w.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        w.installEventFilter(_GUARD)
        w.setProperty("_wheel_guarded", True)


def available_geometry(widget: QWidget) -> QRect | None:
    """The screen area (without task bars) the widget is on, None without a screen."""
    screen = widget.screen() or QGuiApplication.primaryScreen()
    return screen.availableGeometry() if screen is not None else None


def clamp_to_screen(widget: QWidget) -> None:
    """Shrink and move a top-level widget so its frame lies inside the available screen area."""
    area = available_geometry(widget)
    if area is None or area.isEmpty():
        return
    frame = widget.frameGeometry()
    extra_w = frame.width() - widget.width()
    extra_h = frame.height() - widget.height()
    w = min(widget.width(), area.width() - extra_w)
    h = min(widget.height(), area.height() - extra_h)
    if (w, h) != (widget.width(), widget.height()):
        widget.resize(w, h)
    frame = widget.frameGeometry()
    x = max(min(frame.x(), area.right() + 1 - frame.width()), area.left())  # too wide: the left edge stays seen
    y = max(min(frame.y(), area.bottom() + 1 - frame.height()), area.top())
    if (x, y) != (frame.x(), frame.y()):
        widget.move(x, y)
