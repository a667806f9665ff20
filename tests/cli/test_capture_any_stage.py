"""`lps capture --camera sim` rides any stage: the simulated rig follows each move of the operator's stage, so a
manual stage (scripted answers) and a command stage (a script) give the simulated stage's estimate."""
from __future__ import annotations

import io
import json
import stat
import sys

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
PLAN = ["--preset", "small", "--start", "0", "--stop", "8", "--step", "2", "--settle", "0", "--seed", "3"]


def measured(folder) -> np.ndarray:
    assert lps_main(["detect", str(folder)]) == 0
    assert lps_main(["estimate", str(folder)]) == 0
    doc = json.loads((folder / "results.json").read_text())
    return np.array([p["measured_mm"] for p in doc["positions"]])


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> np.ndarray:
    folder = tmp_path_factory.mktemp("sim") / "s"
    assert lps_main(["capture", "--out", str(folder), "--stage", "sim", *PLAN]) == 0
    return measured(folder)


def test_a_manual_stage_confirmed_on_the_terminal_gives_the_simulated_estimate(tmp_path, monkeypatch, capsys, simulated):
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n" * 100))  # the operator presses Enter at every stop
    folder = tmp_path / "manual"
    assert lps_main(["capture", "--out", str(folder), "--stage", "manual", *PLAN]) == 0
    assert "move X to 8.0000 mm, then confirm" in capsys.readouterr().err
    session = json.loads((folder / "session.json").read_text())
    assert session["stage"]["spec"] == "manual" and session["stage"]["driver"] == "ManualStage"
    np.testing.assert_allclose(measured(folder), simulated, rtol=0, atol=1e-9)


def test_a_command_stage_gives_the_simulated_estimate_and_a_failing_script_stops_the_capture(tmp_path, capsys, simulated):
    log = tmp_path / "moves.log"
    fault = tmp_path / "fault"
    fault.write_text("")
    script = tmp_path / "move.sh"  # fails at 6 mm while the fault file exists
    script.write_text(f'#!/bin/sh\nif [ -e "{fault}" ] && [ "$1" = 6.000000 ]; then echo "axis fault" >&2; exit 2; fi\n'
                      f'echo "$1" >> "{log}"\n')
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    folder = tmp_path / "command"
    stage = f"command:{script} {{mm}}"
    assert lps_main(["capture", "--out", str(folder), "--stage", stage, *PLAN]) == 3
    err = capsys.readouterr().err
    assert "move.sh 6.000000` exited with status 2: axis fault" in err and "--resume" in err
    assert f"--resume {folder} --stage '{stage}'" in err  # the hint names the stage again, quoted for a shell
    fault.unlink()  # the operator fixed the stage
    assert lps_main(["capture", "--resume", str(folder)]) == 2  # never the simulated stage in its place
    assert f"give --stage to resume with (it was captured with --stage '{stage}'" in capsys.readouterr().err
    assert lps_main(["capture", "--resume", str(folder), "--stage", stage]) == 0
    assert log.read_text().split()[-1] == "8.000000"
    np.testing.assert_allclose(measured(folder), simulated, rtol=0, atol=1e-9)
