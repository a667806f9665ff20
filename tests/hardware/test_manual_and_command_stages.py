"""The manual stage waits for the operator's confirmation; the command stage runs a program per move."""
from __future__ import annotations

import stat
import sys
import threading

import pytest

from lps_gui.errors import HardwareError, InputError
from lps_gui.hardware.command import CommandStage
from lps_gui.hardware.manual import ManualStage


def test_a_manual_move_asks_with_the_nominal_position_and_reads_back_what_was_confirmed():
    asked: list[str] = []
    stage = ManualStage()
    stage.attach_prompt(asked.append)
    stage.connect()
    stage.move_to(12.5, 600.0)
    assert stage.pending_target() == ("X", 12.5) and stage.status().state == "Run"
    assert stage.wait_idle().work_mm[0] == 12.5 and stage.position_mm() == 12.5
    assert asked == ["move X to 12.5000 mm, then confirm"] and stage.pending_target() is None


def test_the_gui_button_confirms_and_a_stop_gives_up_with_one_line():
    stage = ManualStage()
    stage.connect()
    stage.move_to(3.0, 600.0)
    timer = threading.Timer(0.05, stage.confirm_moved)  # the operator presses Moved
    timer.start()
    assert stage.wait_idle().work_mm[0] == 3.0
    stage.move_to(4.0, 600.0)
    threading.Timer(0.05, stage.stop).start()
    with pytest.raises(HardwareError, match="stopped before the operator confirmed X at 4.0000 mm"):
        stage.wait_idle()
    assert stage.position_mm() == 3.0


def test_end_of_input_on_the_terminal_is_a_one_line_error(monkeypatch):
    import io

    from lps_gui.hardware.manual import terminal_prompt

    monkeypatch.setattr(sys, "stdin", io.StringIO("\n"))
    stage = ManualStage()
    stage.attach_prompt(terminal_prompt)
    stage.connect()
    stage.move_to(1.0, 600.0)
    assert stage.wait_idle().work_mm[0] == 1.0
    stage.move_to(2.0, 600.0)
    with pytest.raises(HardwareError, match="no confirmation \\(end of input\\)"):
        stage.wait_idle()


def _script(tmp_path, body: str):
    path = tmp_path / "move.sh"
    path.write_text(f"#!/bin/sh\n{body}\n")
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return path


def test_the_command_runs_once_per_move_with_the_position_as_one_argument(tmp_path):
    log = tmp_path / "moves.log"
    script = _script(tmp_path, f'echo "$1 $2" >> "{log}"')
    stage = CommandStage(f"'{script}' {{mm}} {{axis}}")
    stage.connect()
    for x in (1.0, -2.25):
        stage.move_to(x, 600.0)
        assert stage.wait_idle().work_mm[0] == x
    assert log.read_text().splitlines() == ["1.000000 X", "-2.250000 X"]


def test_a_failing_or_hanging_command_is_a_one_line_error_naming_it(tmp_path):
    failing = CommandStage(f"{_script(tmp_path, 'echo motor fault >&2; exit 3')} {{mm}}")
    failing.connect()
    with pytest.raises(HardwareError, match=r"move.sh 5.000000` exited with status 3: motor fault"):
        failing.move_to(5.0, 600.0)
    assert failing.position_mm() == 0.0
    slow = CommandStage("sleep 5 {mm}", timeout_s=0.2)
    slow.connect()
    with pytest.raises(HardwareError, match="`sleep 5 1.000000` did not exit within 0.2 s"):
        slow.move_to(1.0, 600.0)
    missing = CommandStage("/nonexistent/mover {mm}")
    missing.connect()
    with pytest.raises(HardwareError, match="cannot run"):
        missing.move_to(1.0, 600.0)
    with pytest.raises(InputError, match="\\{mm\\}"):
        CommandStage("./move.sh")
    with pytest.raises(InputError, match="quotes"):
        CommandStage("'./move.sh {mm}")
