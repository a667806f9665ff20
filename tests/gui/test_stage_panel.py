"""Stage panel on the simulated rig: connect, jog with the readout following, port vanishing, settings."""
from __future__ import annotations

import pytest
from PySide6.QtCore import Qt

from lps_gui.hardware.machine_settings import NUMBER
from lps_gui.hardware.stage import StageSetting
from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui


def readout_mm(window, axis="X") -> float:
    return float(window.stage_panel.readout[axis].text())


def test_connect_jog_and_see_the_readout_change(qtbot, window):
    connect_sim(qtbot, window)
    panel = window.stage_panel
    assert panel.connect_btn.text() == "Disconnect"
    assert "Simulated" in window.status_conn.text()
    qtbot.waitUntil(lambda: panel.readout["X"].text().strip() != "---", timeout=5000)
    x0 = readout_mm(window)
    panel.step.setCurrentIndex(panel.step.findData(10.0))
    panel.feed.setValue(3000.0)
    panel.jog_buttons[("X", +1)].click()
    # the readout follows the carriage (several updates a second) and ends 10 mm further
    qtbot.waitUntil(lambda: abs(readout_mm(window) - (x0 + 10.0)) < 1e-6 and panel.state_label.text() == "Idle",
                    timeout=10000)
    # the status bar's position follows on its own update (it may lag the panel by one status report)
    qtbot.waitUntil(lambda: f"X {x0 + 10:.3f}" in window.status_pos.text(), timeout=10000)
    # keyboard jogging, once the toggle is on: Left arrow moves X back by one step
    panel.keyboard_jog.setChecked(True)
    panel.jog_buttons[("X", -1)].setFocus()
    qtbot.keyClick(panel.jog_buttons[("X", -1)], Qt.Key.Key_Left)
    qtbot.waitUntil(lambda: abs(readout_mm(window) - x0) < 1e-6, timeout=10000)


def test_port_vanishes_while_connected(qtbot, window):
    connect_sim(qtbot, window)
    stage = window.stage_ctl.stage
    stage.disconnect_fault()  # the simulated port disappears now
    qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=5000)
    assert window.last_error is not None
    title, message = window.last_error
    assert title == "Stage connection lost"
    assert "vanished" in message and "\n" not in message
    assert window.stage_panel.connect_btn.text() == "Connect"
    assert window.stage_panel.state_label.text() == "Disconnected"
    assert "not connected" in window.status_conn.text()
    # the operator reconnects: a fresh simulated rig comes up
    connect_sim(qtbot, window)


def test_settings_table_validates_before_writing(qtbot, window):
    panel = window.stage_panel
    panel.show_settings([StageSetting(110, 3000.0, "X max rate", "mm/min"), StageSetting(3, 0.0, "direction invert", "mask")])
    assert panel.settings_table.item(0, 1).text() == "X max rate"
    assert panel.settings_table.item(0, 3).text() == "mm/min"
    panel.settings_table.item(0, 2).setText("fast")
    panel.settings_table.item(1, 2).setText("1.5")
    changes, errors = panel.pending_settings()
    assert changes == [] and len(errors) == 2
    assert errors[0].startswith("110 (X max rate):") and "not a number" in errors[0]  # no stage: its plain number
    assert errors[1].startswith("3 (direction invert):") and "whole number" in errors[1]
    panel.settings_table.item(0, 2).setText("2500")
    panel.settings_table.item(1, 2).setText("1")
    changes, errors = panel.pending_settings()
    assert errors == [] and changes == [(110, 2500.0), (3, 1.0)]


def test_settings_are_read_from_the_connected_stage_and_written(qtbot, window):
    connect_sim(qtbot, window)
    panel = window.stage_panel
    qtbot.waitUntil(lambda: panel.settings_table.rowCount() > 5, timeout=5000)
    rows = {panel.settings_table.item(r, 0).text(): r for r in range(panel.settings_table.rowCount())}
    r = rows["max_rate_mm_min.X"]  # the simulated machine names its settings (GRBL's $110 is the emulator's)
    assert panel.settings_table.item(r, 3).text() == "mm/min"  # a unit is shown
    panel.settings_table.item(r, 2).setText("2400")
    panel.write_settings_btn.click()
    stage = window.stage_ctl.stage
    rate = NUMBER["max_rate_mm_min.X"]
    qtbot.waitUntil(lambda: {s.number: s.value for s in stage.read_settings()}[rate] == 2400.0, timeout=5000)
    # the table is read back after writing and shows the controller's value
    qtbot.waitUntil(lambda: panel._settings and {s.number: s.value for s in panel._settings}[rate] == 2400.0,
                    timeout=5000)
    lo, hi = stage.axis_travel_mm[0]  # the rig's travel, said from its named settings
    assert f"travel X {hi - lo:g} mm" in panel.travel_label.text() and "soft limits ON" in panel.travel_label.text()


def test_grbl_emulator_over_a_pty_and_the_cable_pulled(qtbot, window):
    """The real GRBL driver over a pseudo-terminal: jog, then the port disappears mid-session."""
    panel = window.stage_panel
    panel.select_source("emulator")
    assert panel.source.currentData() == "emulator"
    panel.connect_btn.click()
    qtbot.waitUntil(lambda: window.stage_ctl.connected and window.stage_ctl.last_status is not None, timeout=15000)
    assert window.camera_panel.sim_camera is not None  # the emulator serves the simulated rig: its camera rides it (issue 37)
    qtbot.waitUntil(lambda: panel.readout["X"].text().strip() != "---", timeout=5000)
    x0 = readout_mm(window)
    panel.step.setCurrentIndex(panel.step.findData(1.0))
    panel.feed.setValue(3000.0)
    panel.jog_buttons[("X", +1)].click()
    qtbot.waitUntil(lambda: abs(readout_mm(window) - (x0 + 1.0)) < 1e-3, timeout=10000)
    window.stage_ctl.stage.emulator.drop()  # the USB cable is pulled
    qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=10000)
    title, message = window.last_error
    assert title == "Stage connection lost" and "\n" not in message
    assert panel.connect_btn.text() == "Connect" and panel.connect_btn.isEnabled()
