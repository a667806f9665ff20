"""The stage panel as an operator meets it (issue 13): keys, typed ports, a locked GRBL, homing feedback."""
from __future__ import annotations

import logging
import os

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication

from lps_gui.hardware import serial_ports_by_id
from lps_gui.hardware.grbl.emulator import GrblEmulator
from lps_gui.hardware.sim_stage import SimulatedStage
from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui


def _position(window):
    return window.stage_ctl.stage.status().work_mm


@pytest.fixture
def jogs(window, monkeypatch):
    """Every jog the panel asks the controller for, as (axis, sign)."""
    calls: list[tuple[str, int]] = []
    panel = window.stage_panel
    real = panel.jog
    monkeypatch.setattr(panel, "jog", lambda axis, sign: (calls.append((axis, sign)), real(axis, sign)))
    return calls


def test_a_key_press_in_a_focused_spin_box_does_not_move_the_stage(qtbot, window, jogs):
    connect_sim(qtbot, window)
    panel = window.stage_panel
    qtbot.waitUntil(lambda: window.stage_ctl.last_status is not None, timeout=5000)
    before = _position(window)
    panel.feed.setFocus()
    qtbot.waitUntil(lambda: QApplication.focusWidget() is not None, timeout=2000)
    feed = panel.feed.value()
    qtbot.keyClick(QApplication.focusWidget(), Qt.Key.Key_Up)  # the reported case: Feed box, Up
    assert panel.feed.value() == feed + 1  # the key edited the field...
    panel.step.setFocus()
    qtbot.keyClick(panel.step, Qt.Key.Key_PageUp)
    qtbot.wait(300)
    assert jogs == [] and _position(window) == before  # ...and moved nothing
    assert panel.keyboard_state.text() == "keys jog: off"
    # the explicit toggle still leaves number and list fields their keys
    panel.keyboard_jog.setChecked(True)
    qtbot.keyClick(panel.feed, Qt.Key.Key_Down)
    assert jogs == []


def test_keyboard_jog_only_while_the_toggle_is_on(qtbot, window, jogs):
    """Issue 26 item 8: right after Connect (the Stage panel has focus) arrows do nothing until the toggle is on."""
    panel = window.stage_panel
    assert not panel.keyboard_jog.isChecked()  # off at start
    connect_sim(qtbot, window)
    panel.step.setCurrentIndex(panel.step.findData(1.0))
    panel.feed.setValue(3000.0)
    before = _position(window)
    for w in (panel.connect_btn, panel.jog_area, panel.jog_buttons[("X", -1)], panel.read_settings_btn):
        w.setFocus()
        qtbot.waitUntil(lambda w=w: QApplication.focusWidget() is w, timeout=2000)
        assert panel.keyboard_state.text() == "keys jog: off"
        for key in (Qt.Key.Key_Left, Qt.Key.Key_Right, Qt.Key.Key_Up, Qt.Key.Key_PageUp):
            qtbot.keyClick(w, key)
    qtbot.wait(300)
    assert jogs == [] and _position(window) == before
    panel.keyboard_jog.setChecked(True)
    panel.jog_area.setFocus()
    qtbot.waitUntil(lambda: panel.keyboard_state.text() == "keys jog: ON", timeout=2000)
    y0 = _position(window)[1]
    qtbot.keyClick(panel.jog_area, Qt.Key.Key_Up)
    qtbot.waitUntil(lambda: abs(_position(window)[1] - (y0 + 1.0)) < 1e-6, timeout=10000)
    qtbot.keyClick(panel.read_settings_btn, Qt.Key.Key_Right)
    assert jogs == [("Y", +1), ("X", +1)]
    panel.keyboard_jog.setChecked(False)
    assert panel.keyboard_state.text() == "keys jog: off"


def test_serial_ports_by_id_lists_stable_names(tmp_path):
    (tmp_path / "ttyUSB3").write_text("")
    os.symlink(tmp_path / "ttyUSB3", tmp_path / "usb-1a86_USB_Serial-if00-port0")
    assert serial_ports_by_id(str(tmp_path)) == [
        (str(tmp_path / "ttyUSB3"), str(tmp_path / "ttyUSB3")),
        (str(tmp_path / "usb-1a86_USB_Serial-if00-port0"), str(tmp_path / "ttyUSB3")),
    ]
    assert serial_ports_by_id(str(tmp_path / "missing")) == []


def test_port_box_is_editable_and_lists_by_id_names(qtbot, window, monkeypatch):
    import lps_gui.hardware as hardware

    monkeypatch.setattr(hardware, "serial_ports_by_id", lambda: [("/dev/serial/by-id/usb-FTDI_FT232R-if00-port0", "/dev/ttyUSB0")])
    panel = window.stage_panel
    panel.refresh_sources()
    assert panel.source.isEditable()
    i = panel.source.findData("grbl:/dev/serial/by-id/usb-FTDI_FT232R-if00-port0")
    assert i >= 0 and "ttyUSB0" in panel.source.itemText(i)
    panel.source.setEditText("/dev/pts/77")
    assert panel.current_source() == "grbl:/dev/pts/77"
    panel.source.setEditText("GRBL emulator (pty)")
    assert panel.current_source() == "emulator"
    panel.source.setEditText("my stage")
    assert panel.current_source() is None


@pytest.fixture
def external_grbl():
    """Stock GRBL 1.1h (powers up in Alarm with $22=1) started outside the GUI, e.g. `lps emulate-grbl`."""
    with GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0), start_mm=60.0), time_scale=4.0, homing_init_lock=True) as emu:
        yield emu


def test_typed_pty_of_an_external_grbl_connects_asks_home_or_unlock_and_shows_homing(qtbot, window, external_grbl, caplog):
    caplog.set_level(logging.INFO, logger="lps_gui.gui.stage.controller")
    panel = window.stage_panel
    panel.source.setEditText(external_grbl.path)  # /dev/pts/N typed into the Source box
    panel.connect_btn.click()
    qtbot.waitUntil(lambda: window.stage_ctl.connected, timeout=10000)
    qtbot.waitUntil(lambda: panel._lock_box is not None and panel._lock_box.isVisible(), timeout=5000)  # power-up Alarm
    assert panel.state_label.text() == "Alarm"
    home = next(b for b in panel._lock_box.buttons() if b.text() == "Home")
    home.click()
    assert panel.state_label.text() == "Home"  # at once
    qtbot.waitUntil(lambda: window.stage_ctl.last_status is not None and window.stage_ctl.last_status.state == "Home",
                    timeout=5000)  # and from the controller's reports while the cycle runs
    qtbot.waitUntil(lambda: panel.state_label.text() == "Idle", timeout=20000)
    qtbot.waitUntil(lambda: any("homing finished" in r.getMessage() for r in caplog.records), timeout=5000)
    assert external_grbl.stage.homed
    assert panel.machine["X"].text() == "-99.000"


def test_console_sends_lines_keeps_history_and_shows_replies(qtbot, window, external_grbl):
    panel = window.stage_panel
    panel.source.setEditText(external_grbl.path)
    panel.connect_btn.click()
    qtbot.waitUntil(lambda: window.stage_ctl.connected and panel.console.line.isEnabled(), timeout=10000)
    console = panel.console
    for line in ("$X", "$I"):
        console.line.setText(line)
        qtbot.keyClick(console.line, Qt.Key.Key_Return)
    qtbot.waitUntil(lambda: "[VER:1.1h" in console.transcript.toPlainText(), timeout=5000)
    text = console.transcript.toPlainText()
    assert "> $X" in text and "[MSG:Caution: Unlocked]" in text and "[OPT:V,15,128]" in text
    qtbot.keyClick(console.line, Qt.Key.Key_Up)  # history, not a jog
    assert console.line.text() == "$I"
    qtbot.keyClick(console.line, Qt.Key.Key_Up)
    assert console.line.text() == "$X"
    qtbot.keyClick(console.line, Qt.Key.Key_Down)
    qtbot.keyClick(console.line, Qt.Key.Key_Down)
    assert console.line.text() == ""
    console.line.setText("G0 X999")  # beyond the travel: the alarm comes back as one line
    console.send()
    qtbot.waitUntil(lambda: "ALARM:2" in console.transcript.toPlainText(), timeout=5000)
    assert "travel X 100 mm" in panel.travel_label.text() and "soft limits ON" in panel.travel_label.text()
    panel.reset_btn.click()  # the alarm needs a reset; then unlock and go to a position
    qtbot.waitUntil(lambda: window.stage_ctl.last_status.state == "Alarm" and not window.stage_ctl.stage._critical,
                    timeout=5000)
    window.stage_ctl.call("unlock", "unlock")
    panel.goto_axis.setCurrentIndex(panel.goto_axis.findData("X"))
    panel.goto_target.setValue(42.5)
    panel.feed.setValue(3000.0)
    qtbot.waitUntil(lambda: window.stage_ctl.last_status.state == "Idle", timeout=5000)
    panel.goto_btn.click()
    qtbot.waitUntil(lambda: abs(float(panel.readout["X"].text()) - 42.5) < 1e-6, timeout=10000)
    machine = float(panel.machine["X"].text())
    assert panel.zero_buttons["X"].isEnabled() and panel.work_system.currentData() == "G54"
    panel.zero_buttons["X"].click()  # asks first, naming the system it changes
    box = panel.dro.zero_box
    assert box is not None and "G54" in box.text() and "G54" in box.windowTitle()
    box.button(box.StandardButton.Yes).click()  # the work zero moves here; the machine position does not
    qtbot.waitUntil(lambda: abs(float(panel.readout["X"].text())) < 1e-6, timeout=10000)
    qtbot.waitUntil(lambda: abs(float(panel.offset["X"].text()) - machine) < 1e-6, timeout=5000)  # GRBL's sign
    assert float(panel.machine["X"].text()) == pytest.approx(machine)
    assert window.stage_ctl.stage.work_offsets()["G54"][0] == pytest.approx(machine)  # $# agrees with the DRO
    assert external_grbl.stage.status().work_mm[0] == pytest.approx(42.5)


def test_console_is_disabled_for_the_simulated_stage_and_axes_can_be_hidden(qtbot, window):
    connect_sim(qtbot, window)
    panel = window.stage_panel
    assert not panel.console.line.isEnabled() and "no G-code console" in panel.console.line.placeholderText()
    assert panel.zero_buttons["X"].isEnabled() and panel.work_system.isEnabled()  # GRBL's work offset model
    panel.axes.setCurrentIndex(panel.axes.findData("X"))
    assert panel.readout["X"].isVisible() and not panel.readout["Y"].isVisible()
    assert not panel.jog_buttons[("Z", +1)].isVisible()


def test_press_and_hold_jogs_until_released(qtbot, window):
    connect_sim(qtbot, window)
    panel = window.stage_panel
    panel.step.setCurrentIndex(panel.step.findData(0.0))
    panel.feed.setValue(1200.0)  # 20 mm/s
    x0 = _position(window)[0]
    button = panel.jog_buttons[("X", +1)]
    qtbot.mousePress(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: _position(window)[0] > x0 + 3.0, timeout=10000)  # keeps going while held
    qtbot.mouseRelease(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: window.stage_ctl.stage.status().state == "Idle", timeout=5000)
    stopped = _position(window)[0]
    qtbot.wait(400)
    assert _position(window)[0] == stopped  # released: no queued jog runs on


def test_an_emulator_started_elsewhere_appears_in_the_source_list(qtbot, window, tmp_path, monkeypatch):
    """Issue 26 item 12: `lps emulate-grbl` announces its pty; the panel lists it without Refresh."""
    import lps_gui.hardware.announce as announce

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    panel = window.stage_panel
    with GrblEmulator(SimulatedStage(travel_mm=(0.0, 100.0)), time_scale=4.0) as emu:
        withdraw = announce.announce(emu.path)
        assert announce.announced_ports() == [emu.path]
        panel._watch_ports()  # what the timer does every few seconds
        i = panel.source.findData(f"grbl:{emu.path}")
        assert i >= 0 and "emulator" in panel.source.itemText(i)
        assert panel.source.currentData() == "sim"  # the choice is kept
        withdraw()
    panel._watch_ports()
    assert panel.source.findData(f"grbl:{emu.path}") < 0
    (announce.announce_dir() / "999999999").write_text("/dev/pts/999\n")  # a dead emulator's file
    assert announce.announced_ports() == [] and not (announce.announce_dir() / "999999999").exists()
