"""`lps capture --stage zaber:PTY` and `thorlabs:PTY` with the simulated camera: the vendor library is the client,
the emulator answers as the manual says, and the estimate equals the simulated stage's (SPEC 16)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.thorlabs_emulator import ThorlabsEmulator
from lps_gui.hardware.zaber_emulator import ZaberEmulator

# stops on whole device units (a Zaber X-LSM microstep is 3.048 um / 64; a KDC101 + Z8 count is 1 / 34304 mm), so the
# position each controller reports is exactly the commanded one
PLANS = {
    "zaber": ["--preset", "small", "--start", "0", "--stop", "12.192", "--step", "3.048", "--settle", "0", "--seed", "3"],
    "thorlabs": ["--preset", "small", "--start", "0", "--stop", "8", "--step", "2", "--settle", "0", "--seed", "3"],
}
EMULATORS = {"zaber": ZaberEmulator, "thorlabs": ThorlabsEmulator}


def measured(folder) -> np.ndarray:
    assert lps_main(["detect", str(folder)]) == 0
    assert lps_main(["estimate", str(folder)]) == 0
    return np.array([p["measured_mm"] for p in json.loads((folder / "results.json").read_text())["positions"]])


@pytest.mark.parametrize("kind", ["zaber", "thorlabs"])
def test_a_capture_on_a_vendor_stage_gives_the_simulated_estimate(tmp_path, kind):
    reference = tmp_path / "sim"
    assert lps_main(["capture", "--out", str(reference), "--stage", "sim", *PLANS[kind]]) == 0
    folder = tmp_path / kind
    with EMULATORS[kind](SimulatedStage(travel_mm=(-10.0, 100.0)), time_scale=50.0) as emu:
        assert lps_main(["capture", "--out", str(folder), "--stage", f"{kind}:{emu.path}", *PLANS[kind]]) == 0
    session = json.loads((folder / "session.json").read_text())
    assert session["stage"]["spec"] == f"{kind}:{emu.path}"
    np.testing.assert_allclose(measured(folder), measured(reference), rtol=0, atol=1e-9)


def test_the_session_names_the_driver_and_the_capabilities_it_declared(tmp_path):
    folder = tmp_path / "z"
    with ZaberEmulator(SimulatedStage(travel_mm=(-10.0, 100.0)), time_scale=50.0) as emu:
        assert lps_main(["capture", "--out", str(folder), "--stage", f"zaber:{emu.path}", *PLANS["zaber"]]) == 0
    stage = json.loads((folder / "session.json").read_text())["stage"]
    assert stage["driver"] == "ZaberStage" and stage["capabilities"] == ["home", "settings", "jog", "feed_hold"]
