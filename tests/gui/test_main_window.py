"""The main window: docks and menus, remembered settings, missing back ends, screenshot CLI."""
from __future__ import annotations

import pytest

from lps_gui.core.planning.plan import Plan

pytestmark = pytest.mark.gui


def test_panels_menus_and_defaults(window):
    assert set(window.docks) == {"stage", "camera", "intrinsics", "capture", "estimation", "results", "log"}
    menus = [a.text() for a in window.menuBar().actions()]
    assert menus == ["&File", "&Stage", "&Run", "&View", "&Help"]
    assert window.stage_panel.source.currentData() == "sim"  # the simulated rig on first start
    assert "not connected" in window.status_conn.text()
    # every figure has its tab (titles and axis labels with units) before any result exists
    rp = window.results_panel
    assert set(rp.plots) >= {"positions", "deviation", "step", "straightness", "angles", "residuals"}
    assert "[mm]" in rp.plots["positions"].getPlotItem().getAxis("bottom").labelText


def test_settings_are_remembered(make_window, settings):
    w1 = make_window()
    w1.capture_panel.set_plan(Plan(start_mm=5.0, stop_mm=25.0, step_mm=5.0, directions="both", runs=3))
    w1.estimation_panel.method.setCurrentIndex(w1.estimation_panel.method.findData("hybrid"))
    w1.stage_panel.select_source("emulator")
    w1.settings.setValue("stage/source", "emulator")
    w1.remember_folder("/tmp/somewhere")
    w1.docks["log"].hide()
    w1.save_settings()
    w2 = make_window(settings_=settings)
    plan = w2.capture_panel.plan()
    assert (plan.start_mm, plan.stop_mm, plan.step_mm, plan.directions, plan.runs) == (5.0, 25.0, 5.0, "both", 3)
    assert w2.estimation_panel.method.currentData() == "hybrid"
    assert w2.stage_panel.source.currentData() == "emulator"
    assert w2.last_folder() == "/tmp/somewhere"
    assert w2.docks["log"].isHidden()


def test_estimate_without_a_session_says_what_to_do(qtbot, window):
    window.estimation_panel.run_btn.click()
    assert window.last_error == ("Cannot start", "estimation: choose a session folder first")


def test_screenshot_cli_renders_offscreen(tmp_path):
    from PySide6.QtGui import QImage

    from lps_gui.gui.app import main

    png = tmp_path / "w.png"
    assert main(["--screenshot", str(png), "--size", "1200x800", "--settings", str(tmp_path / "s.ini")]) == 0
    img = QImage(str(png))
    assert (img.width(), img.height()) == (1200, 800)


def test_screenshot_of_a_missing_session_fails_with_one_line(tmp_path, capsys):
    from lps_gui.gui.app import main

    assert main(["--screenshot", str(tmp_path / "w.png"), "--session", str(tmp_path / "nowhere"),
                 "--settings", str(tmp_path / "s.ini")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"lps-gui: {tmp_path / 'nowhere'}: session folder not found; check the path"]
    assert not (tmp_path / "w.png").exists()


def test_the_window_uses_what_panels_expose_not_their_child_widgets(window):
    """Issue 23: no `stage_panel.baud`, `estimation_panel.method.findData` in the window."""
    import inspect
    import re

    from PySide6.QtWidgets import QWidget

    import lps_gui.gui.main_window as main_window

    chains = set(re.findall(r"self\.(\w+_panel)\.(\w+)\.\w+", inspect.getsource(main_window)))
    assert chains  # signals are used this way
    reached = [f"{p}.{a}" for p, a in chains if isinstance(getattr(getattr(window, p), a, None), QWidget)]
    assert reached == []


def test_the_camera_defaults_to_the_simulated_one_while_the_simulated_stage_is_chosen(window):
    cam, stage = window.camera_panel, window.stage_panel
    assert stage.current_source() == "sim" and cam.source.currentData() == "sim"
    stage.select_source("grbl:/dev/ttyUSB9")  # a GRBL controller on a port: nothing simulated rides it
    assert cam.source.findData("sim") < 0 and cam.source.currentData() == "0"
    stage.select_source("emulator")  # the emulator serves the simulated rig: its camera comes along (issue 37)
    assert cam.source.findData("sim") >= 0
    stage.select_source("sim")
    assert cam.source.currentData() == "sim"
    cam.start()  # before the stage is connected: one line saying what to do, nothing opened
    assert cam.grabber is None and "connect" in window.last_error[1]
