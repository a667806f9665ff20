"""Marlin 2.x: the emulator answers as queue.cpp / gcode.cpp do; the driver streams numbered, checksummed lines
through resends and busy messages; `lps capture --stage marlin:PTY --camera sim` gives the simulated stage's
estimate, and a port that vanishes mid-capture is one line and `--resume` goes on."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.clock import SimClock
from lps_gui.errors import HardwareError
from lps_gui.hardware import open_stage
from lps_gui.hardware.capabilities import Console, Settings, declared
from lps_gui.hardware.marlin.driver import MarlinStage, checksum
from lps_gui.hardware.marlin.emulator import MarlinEmulator, MarlinFaults
from lps_gui.hardware.sim_stage import SimulatedStage
from tests.hardware.grbl_port import SteppedPort

PLAN = ["--preset", "small", "--start", "0", "--stop", "8", "--step", "2", "--settle", "0", "--seed", "3"]


def numbered(n: int, cmd: str) -> bytes:
    body = f"N{n} {cmd}"
    return f"{body}*{checksum(body)}\n".encode()


@pytest.fixture
def port():
    with MarlinEmulator(SimulatedStage(travel_mm=(0.0, 100.0), clock=SimClock()), stepped=True) as emu:
        p = SteppedPort(emu)
        p.pending()  # whatever of the power-up banner is left
        yield p
        p.close()


def test_line_numbers_and_checksums_are_checked_as_queue_cpp_does(port):
    marlin_ok = port.ask(numbered(1, "M110 N0"))  # M110 on line 1 sets the line number to 0
    assert marlin_ok == ["ok"]
    assert port.ask(numbered(2, "G90"), 3) == [
        "Error:Line Number is not Last Line Number+1, Last Line: 0", "Resend: 1", "ok"]
    assert port.ask(b"N1 G90\n", 3) == ["Error:No Checksum with line number, Last Line: 0", "Resend: 1", "ok"]
    assert port.ask(b"N1 G90*1\n", 3) == ["Error:checksum mismatch, Last Line: 0", "Resend: 1", "ok"]
    assert port.ask(numbered(1, "G90")) == ["ok"]
    assert port.ask(b"M110 N41\n") == ["ok"] and port.ask(numbered(42, "M114"), 2) == [
        "X:0.00 Y:0.00 Z:0.00 E:0.00 Count X:0 Y:0 Z:0", "ok"]
    assert port.ask(b"M999\n", 2) == ['echo:Unknown command: "M999"', "ok"]


def test_m400_answers_once_the_move_ended_and_says_busy_every_two_seconds_meanwhile(port):
    assert port.ask(b"G1 X20 F300\n") == ["ok"]  # planned, not done: 4 s at 5 mm/s
    port.send(b"M400\n")
    assert port.pending() == []
    port.advance(2.05)
    assert port.pending() == ["echo:busy: processing"]
    port.advance(3.0)
    assert port.pending() == ["echo:busy: processing", "ok"]
    assert port.ask(b"M114\n", 2)[0].startswith("X:20.00 ")
    assert port.ask(b"G0 X500\n") == ["ok"]  # soft endstops clamp the move to the travel
    port.advance(30.0)
    assert port.ask(b"M114\n", 2)[0].startswith("X:100.00 ")


def test_the_driver_moves_reads_settings_and_resends_what_line_noise_spoiled():
    faults = MarlinFaults(corrupt_every=3)  # every third line arrives spoiled: Error, Resend, ok
    with MarlinEmulator(SimulatedStage(travel_mm=(0.0, 100.0)), faults=faults, time_scale=50.0) as emu:
        stage = open_stage(f"marlin:{emu.path}")
        assert isinstance(stage, MarlinStage) and declared(stage) == ["settings", "console"]
        assert isinstance(stage, Settings) and isinstance(stage, Console) and stage.can_home
        for x in (12.5, 3.25, 40.0):
            stage.move_to(x, 3000.0)
            assert stage.wait_idle(timeout_s=30.0).work_mm[0] == x
        settings = {s.number: s for s in stage.read_settings()}
        assert settings[920].value == 80.0 and settings[2030].unit == "mm/s" and settings[2010].name == "X max acceleration"
        stage.write_setting(920, 100.0)
        assert {s.number: s.value for s in stage.read_settings()}[920] == 100.0
        with pytest.raises(HardwareError, match='Unknown command: "M999"'):
            stage.command("M999")
        stage.home()
        assert stage.position_mm() == pytest.approx(emu.stage.status().work_mm[0], abs=0.005)
        assert stage.resends >= (emu.lines_received - stage.resends) // 3 > 3  # each spoiled line was sent again
        stage.disconnect()


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> np.ndarray:
    folder = tmp_path_factory.mktemp("sim") / "s"
    assert lps_main(["capture", "--out", str(folder), "--stage", "sim", *PLAN]) == 0
    return measured(folder)


def measured(folder) -> np.ndarray:
    assert lps_main(["detect", str(folder)]) == 0
    assert lps_main(["estimate", str(folder)]) == 0
    return np.array([p["measured_mm"] for p in json.loads((folder / "results.json").read_text())["positions"]])


def test_a_capture_on_marlin_gives_the_simulated_estimate_and_resumes_after_the_port_vanished(tmp_path, capsys, simulated):
    folder = tmp_path / "marlin"
    with MarlinEmulator(SimulatedStage(travel_mm=(-10.0, 100.0)), faults=MarlinFaults(drop_after_lines=20),
                        time_scale=50.0) as emu:
        assert lps_main(["capture", "--out", str(folder), "--stage", f"marlin:{emu.path}", *PLAN]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    gone = [ln for ln in err if "the port is gone" in ln]
    assert gone and f"Marlin on {emu.path}" in gone[0] and "--resume" in err[-1]
    kept = (folder / "captures.jsonl").read_text().splitlines()
    assert 0 < len(kept) < 10
    with MarlinEmulator(SimulatedStage(travel_mm=(-10.0, 100.0)), time_scale=50.0) as emu:
        assert lps_main(["capture", "--resume", str(folder), "--stage", f"marlin:{emu.path}"]) == 0
    session = json.loads((folder / "session.json").read_text())
    assert session["stage"]["driver"] == "MarlinStage"
    np.testing.assert_allclose(measured(folder), simulated, rtol=0, atol=1e-9)


def test_lps_emulate_marlin_serves_a_pty_the_driver_drives_until_ctrl_c():
    import signal
    import subprocess

    from tests.cli.test_emulate_grbl import LPS, _default_sigint, _stop

    proc = subprocess.Popen([*LPS, "emulate", "marlin", "--time-scale", "50", "--travel", "0", "100"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)
    try:
        path = proc.stdout.readline().strip()
        stage = open_stage(f"marlin:{path}")
        stage.move_to(25.0, 3000.0)
        assert stage.wait_idle(timeout_s=30.0).work_mm[0] == 25.0
        stage.disconnect()
    finally:
        out, err = _stop(proc, signal.SIGINT)
    assert proc.returncode == 0 and f"marlin emulator on {path}" in err and "--stage marlin:" in err
