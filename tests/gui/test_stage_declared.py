"""The stage panel shows what the connected stage declares: no settings, jog pad or unlock for a manual stage,
a Moved button that completes its move; a Marlin's M503 settings under its own title with the console."""
from __future__ import annotations

import pytest

from lps_gui.hardware.marlin.emulator import MarlinEmulator
from lps_gui.hardware.sim_stage import SimulatedStage
from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui


def _connect(qtbot, panel, source: str) -> None:
    panel.source.setEditText(source)
    panel.connect_btn.click()
    qtbot.waitUntil(lambda: panel.controller.connected and panel.controller.last_status is not None, timeout=10000)


def test_a_manual_stage_shows_only_the_moved_button_and_the_button_completes_the_move(qtbot, window):
    panel = window.stage_panel
    _connect(qtbot, panel, "manual")
    tabs = panel.lower_tabs
    assert not panel.jog_area.isVisibleTo(panel) and not panel.unlock_btn.isVisibleTo(panel)
    assert not panel.reset_btn.isVisibleTo(panel) and not panel.resume_btn.isVisibleTo(panel)
    assert not tabs.isTabVisible(tabs.indexOf(panel.settings_page)) and not tabs.isTabVisible(tabs.indexOf(panel.console))
    assert panel.moved_btn.isVisibleTo(panel) and panel.moved_btn.isEnabled() and not panel.home_btn.isEnabled()
    stage = panel.controller.stage
    panel.goto_target.setValue(7.5)
    panel.go_to()  # the stage thread now waits for the operator
    qtbot.waitUntil(lambda: stage.pending_target() == ("X", 7.5), timeout=5000)
    fut = panel.controller.call("wait", "wait_idle")
    panel.moved_btn.click()
    qtbot.waitUntil(lambda: fut.done(), timeout=5000)
    assert fut.result().work_mm[0] == 7.5
    failures: list[str] = []
    panel.controller.command_failed.connect(lambda what, msg: failures.append(msg))
    window.stage_ctl.call("unlock", "unlock")  # the Stage menu's entry: refused in one line, nothing probed further
    assert failures and "ManualStage" in failures[-1] and "cannot do this" in failures[-1]


def test_marlin_shows_its_settings_and_console_and_the_sim_keeps_every_widget(qtbot, window):
    panel = window.stage_panel
    connect_sim(qtbot, window)
    tabs = panel.lower_tabs
    assert panel.jog_area.isVisibleTo(panel) and panel.unlock_btn.isVisibleTo(panel) and not panel.moved_btn.isVisibleTo(panel)
    assert tabs.isTabVisible(tabs.indexOf(panel.settings_page)) and tabs.tabText(tabs.indexOf(panel.settings_page)) == "Simulated machine settings"
    window.stage_ctl.detach("test")
    qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=5000)
    with MarlinEmulator(SimulatedStage(travel_mm=(0.0, 100.0)), time_scale=20.0) as emu:
        _connect(qtbot, panel, f"marlin:{emu.path}")
        assert tabs.tabText(tabs.indexOf(panel.settings_page)) == "Marlin settings (M503)"
        assert tabs.isTabVisible(tabs.indexOf(panel.console)) and "M503" in panel.console.line.placeholderText()
        assert not panel.jog_area.isVisibleTo(panel) and not panel.unlock_btn.isVisibleTo(panel)
        qtbot.waitUntil(lambda: panel.settings_table.rowCount() == 9, timeout=10000)
        assert panel.settings_table.item(0, 1).text() == "X steps per mm" and panel.settings_table.item(0, 0).text() == "M92 X"
        assert "soft endstops" in panel.travel_label.text()
        window.stage_ctl.detach("test")
        qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=5000)
