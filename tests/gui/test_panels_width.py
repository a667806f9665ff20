"""The panels at 1000x700 (issue 37): no sideways scroll bar in the stage dock for any kind of stage connected, nor in
any other dock that scrolls."""
from __future__ import annotations

import stat
from contextlib import ExitStack, nullcontext

import pytest
from PySide6.QtWidgets import QApplication, QScrollArea

from lps_gui.hardware.marlin.emulator import MarlinEmulator
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.zaber_emulator import ZaberEmulator
from tests.hardware.conftest import _zaber_device_db_offline  # noqa: F401  (zaber-motion offline: the manual's units)

pytestmark = pytest.mark.gui

LAPTOP = (1000, 700)


def _source(kind: str, stack: ExitStack, tmp_path) -> str:
    if kind == "marlin":
        return "marlin:" + stack.enter_context(MarlinEmulator(SimulatedStage(travel_mm=(0.0, 100.0)), time_scale=20.0)).path
    if kind == "zaber":
        return "zaber:" + stack.enter_context(ZaberEmulator(SimulatedStage(travel_mm=(-10.0, 100.0)), time_scale=50.0)).path
    if kind == "command":
        script = tmp_path / "move.sh"
        script.write_text("#!/bin/sh\nexit 0\n")
        script.chmod(script.stat().st_mode | stat.S_IEXEC)
        return f"command:{script} {{mm}}"
    return kind  # sim, emulator (the GRBL emulator serving the simulated rig), manual


def _sideways(window) -> tuple[bool, int, int]:
    area = window.docks["stage"].widget()
    assert isinstance(area, QScrollArea)
    return area.horizontalScrollBar().isVisible(), area.widget().minimumSizeHint().width(), area.viewport().width()


@pytest.mark.parametrize("kind", ["sim", "emulator", "marlin", "zaber", "manual", "command"])
def test_the_stage_panel_needs_no_sideways_scrolling_at_1000_px(qtbot, window, monkeypatch, tmp_path, kind):
    import lps_gui.gui.main_window as main_window

    monkeypatch.setattr(main_window, "clamp_to_screen", lambda w: None)  # offscreen's screen is 800x600: not a laptop's
    window.resize(*LAPTOP)
    window.default_layout()  # View > Reset layout: the docks' shares of this width
    window.show_panel("stage")
    panel = window.stage_panel
    with ExitStack() as stack:
        source = _source(kind, stack, tmp_path)
        if kind == "sim":
            assert panel.current_source() == "sim"
        else:
            panel.source.setEditText(source)
        panel.connect_btn.click()
        qtbot.waitUntil(lambda: panel.controller.connected and panel.controller.last_status is not None, timeout=15000)
        qtbot.wait(50)
        QApplication.processEvents()
        shown, need, have = _sideways(window)
        assert window.width() <= LAPTOP[0]
        assert not shown, f"{kind}: the panel needs {need} px, its dock shows {have} px"
        window.stage_ctl.detach("test")
        qtbot.waitUntil(lambda: not window.stage_ctl.connected, timeout=5000)


def test_no_scrolled_panel_needs_sideways_scrolling_at_1000_px(qtbot, window, monkeypatch):
    import lps_gui.gui.main_window as main_window

    monkeypatch.setattr(main_window, "clamp_to_screen", lambda w: None)
    window.resize(*LAPTOP)
    window.default_layout()
    for name in main_window.SCROLLED:
        window.show_panel(name)
        qtbot.wait(20)
        QApplication.processEvents()
        area = window.docks[name].widget()
        assert not area.horizontalScrollBar().isVisible(), (
            f"{name}: the panel needs {area.widget().minimumSizeHint().width()} px, its dock shows "
            f"{area.viewport().width()} px")
