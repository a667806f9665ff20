"""The window on a 1000 px screen (issue 26 item 9): panels scroll, the window never outgrows the screen, no wheel edits."""
from __future__ import annotations

import pytest
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import QAbstractSpinBox, QApplication, QComboBox

pytestmark = pytest.mark.gui

SCREEN_H = 1000


def _expand_everything(window) -> None:
    window.capture_panel.report_setup.toggle.setChecked(True)
    window.capture_panel.planar_editor.enabled.setChecked(True)
    for name in window.docks:
        window.show_panel(name)


def _fits(qtbot, window) -> None:
    qtbot.wait(50)
    QApplication.processEvents()
    assert window.minimumSizeHint().height() <= SCREEN_H
    assert window.minimumHeight() <= SCREEN_H
    assert window.frameGeometry().height() <= SCREEN_H, window.frameGeometry()


def test_the_window_stays_within_a_1000_px_screen_with_every_section_expanded(qtbot, window, monkeypatch):
    import lps_gui.gui.main_window as main_window

    monkeypatch.setattr(main_window, "clamp_to_screen", lambda w: None)  # offscreen's screen is 800x600: not it
    window.resize(1600, SCREEN_H - 40)
    _fits(qtbot, window)
    _expand_everything(window)
    _fits(qtbot, window)
    window.default_layout()  # View > Reset layout
    _fits(qtbot, window)
    assert window.docks["stage"].width() < 560


def test_a_saved_geometry_larger_than_the_screen_is_clamped(qtbot, window):
    from lps_gui.gui.fit import available_geometry, clamp_to_screen

    area = available_geometry(window)
    window.resize(area.width() + 500, area.height() + 500)
    clamp_to_screen(window)
    frame = window.frameGeometry()
    assert frame.height() <= area.height()
    assert frame.height() <= area.height() and frame.top() >= area.top() and frame.left() >= area.left()
    assert window.minimumSizeHint().width() < 1280  # a 1280 px wide screen takes it


def test_a_long_error_does_not_widen_the_left_dock(qtbot, window):
    window.resize(1600, SCREEN_H - 40)
    window.show_panel("capture")
    qtbot.wait(50)
    width = window.docks["capture"].width()
    panel_width = window.capture_panel.width()  # the panel may be wider than its dock (it scrolls sideways)
    window.capture_panel.eta.setText("stopped: " + "a very long reason that goes on and on " * 12)
    qtbot.wait(50)
    assert window.docks["capture"].width() == width and window.capture_panel.width() == panel_width
    eta = window.capture_panel.eta
    assert eta.wordWrap() and eta.width() <= panel_width


def test_the_wheel_over_an_unfocused_field_does_not_edit_it(qtbot, window):
    editor = window.capture_panel.planar_editor
    editor.enabled.setChecked(True)
    window.show_panel("capture")
    combo = editor.pattern
    before = combo.currentIndex()
    fields = window.findChildren(QAbstractSpinBox) + window.findChildren(QComboBox)
    assert fields and all(f.focusPolicy() != Qt.FocusPolicy.WheelFocus for f in fields)
    for w in (combo, window.stage_panel.feed):
        value = w.currentIndex() if w is combo else w.value()
        pos = QPointF(w.rect().center())
        ev = QWheelEvent(pos, QPointF(w.mapToGlobal(pos.toPoint())), QPoint(0, 0), QPoint(0, -120),
                         Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier, Qt.ScrollPhase.NoScrollPhase, False)
        QApplication.sendEvent(w, ev)
        assert (w.currentIndex() if w is combo else w.value()) == value
    assert combo.currentIndex() == before
