"""Errors worded for the window (issue 26 item 11): no CLI switches, no class names, no stale results after a failure."""
from __future__ import annotations

import logging

import numpy as np
import pytest

from lps_gui.errors import HardwareError, InputError
from lps_gui.gui.wording import for_gui
from lps_gui.gui.workers import Job, one_line
from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui

CLI_MESSAGES = (  # raised below the GUI, written for `lps`
    "/tmp/s: already holds a session; use --resume or choose an empty folder",
    "/tmp/s/session.json: has no intrinsics; pass --intrinsics FILE or run `lps intrinsics` first",
    "/tmp/s: not captured on the simulated rig; resume it with --stage and --camera",
    "camera sim: the simulated camera rides the simulated stage; choose the simulated stage (--stage sim)",
    "intrinsics: the board was found in none of the 3 images; check --board matches the printed board",
    "views: check the corners (`lps detect --force`) and the intrinsics",
    "/tmp: folder not found; create it or choose another --out",
)


@pytest.mark.parametrize("message", CLI_MESSAGES)
def test_cli_switches_become_gui_words(message):
    text = for_gui(message)
    assert "--" not in text and "`lps" not in text
    assert text.split(":")[0] == message.split(":")[0]  # the thing it names stays first


def test_user_errors_carry_no_class_name_and_bugs_do():
    assert one_line(InputError("x: use --resume or choose an empty folder")).startswith("x: resume it (Capture")
    assert one_line(HardwareError("port gone\ntrace")) == "port gone"
    assert one_line(PermissionError(13, "Permission denied", "/dev/ttyUSB0")).startswith("[Errno 13] Permission denied")
    assert one_line(KeyError("k")).startswith("KeyError")


def _fail(**_kw):
    raise InputError("session: use --resume or choose an empty folder")


def test_a_failed_job_logs_one_gui_line_no_traceback_no_duration_and_resets_progress(qtbot, window):
    job = Job("estimate s1", _fail)
    window.runner.progress.setRange(0, 10)
    window.run_job(job)
    qtbot.waitUntil(lambda: window.last_error is not None and not window.jobs, timeout=10000)
    log_text = window.log_panel.text()
    assert "lps_gui.errors" not in log_text and "InputError" not in log_text and "Traceback" not in log_text
    assert "estimate s1: finished in" not in log_text and "--resume" not in log_text
    assert "resume it (Capture: Resume session…)" in window.last_error[1]
    assert window.runner.progress.value() == -1 and not window.runner.progress.isVisible()


def test_the_log_follows_the_newest_line(qtbot, window):
    panel = window.log_panel
    window.show_panel("log")
    for i in range(300):
        panel.append(f"line {i}", logging.INFO if i % 3 else logging.WARNING)
    bar = panel.view.verticalScrollBar()
    assert bar.maximum() > 0 and bar.value() == bar.maximum()
    bar.setValue(0)  # the reader scrolls up: new lines do not pull the view away
    panel.append("one more")
    assert bar.value() == 0


def test_a_failed_intrinsics_run_clears_the_old_parameters_and_save(qtbot, window, tmp_path):
    import cv2

    from lps_gui.core.truth.simulate import preset

    panel = window.intrinsics_panel
    panel.set_intrinsics(preset("small").rig.intrinsics)  # an earlier calibration on screen
    assert panel.save_btn.isEnabled() and panel.table.rowCount() > 0
    paths = []
    for i in range(3):  # no board in any of them
        p = tmp_path / f"blank{i}.png"
        cv2.imwrite(str(p), np.full((240, 320), 128, np.uint8))
        paths.append(p)
    panel.add_images(paths)
    panel.start()
    qtbot.waitUntil(lambda: panel.message.text().startswith("failed"), timeout=30000)
    assert panel.table.rowCount() == 0 and not panel.save_btn.isEnabled() and panel.intrinsics is None
    assert "--" not in panel.message.text()


def test_a_camera_that_fails_to_open_leaves_no_old_frame_or_figures(qtbot, window, tmp_path):
    cam = window.camera_panel
    cam.sharpness_label.setText("sharpness 264")
    cam.fps_label.setText("1.3 fps")
    cam.image.setImage(np.zeros((4, 4), np.uint8))
    cam.source.addItem("missing file", str(tmp_path / "missing.avi"))
    cam.source.setCurrentIndex(cam.source.count() - 1)
    cam.start()
    qtbot.waitUntil(lambda: cam.grabber is None, timeout=10000)
    assert cam.image.image is None
    assert cam.sharpness_label.text() == "sharpness —" and cam.fps_label.text() == "— fps"
    assert cam.detect_label.text() == "not opened"


def test_console_placeholder_follows_the_connected_stage(qtbot, window):
    line = window.stage_panel.console.line
    assert "connect a stage with a console" in line.placeholderText()
    connect_sim(qtbot, window)
    assert "no G-code console" in line.placeholderText()
    window.stage_ctl.detach("test")
    assert "connect a stage with a console" in line.placeholderText()


def test_a_stopped_capture_says_frames_are_kept_only_when_there_are_some(window):
    panel = window.capture_panel
    panel.progress.reset()
    assert "no frame was captured" in panel._kept()
    panel.progress.setMaximum(10)
    panel.progress.setValue(3)
    assert "captured frames are kept" in panel._kept()
