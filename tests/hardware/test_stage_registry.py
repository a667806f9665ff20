"""One registry of stage kinds; every kind opens from its spec and declares its capabilities (no probing)."""
from __future__ import annotations

import pytest

from lps_gui.errors import InputError
from lps_gui.hardware import open_stage
from lps_gui.hardware.capabilities import (
    Alarms, Console, FeedHold, Jogging, OperatorMoved, Settings, WorkCoordinates, declared,
)
from lps_gui.hardware.grbl.driver import GrblStage
from lps_gui.hardware.registry import KINDS, emulated_kinds, kind_of, source_from_text, specs_help, stage_choices
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.hardware.stage import Stage


def test_every_spec_finds_its_kind_and_a_wrong_one_lists_them_all():
    assert kind_of("grbl:/dev/ttyUSB0").name == "grbl" and kind_of("sim").name == "sim"
    assert kind_of("command:./move.sh {mm}").name == "command" and kind_of("manual").name == "manual"
    with pytest.raises(InputError, match="not understood; use sim \\| emulator \\| grbl:PORT"):
        kind_of("grbl:")  # a scheme without its port
    with pytest.raises(InputError, match="manual"):
        kind_of("zaber")
    assert all(k.help.split(": ", 1)[0] in specs_help() for k in KINDS)
    assert "grbl" in emulated_kinds()


def test_a_typed_port_is_a_source_and_every_serial_kind_is_offered_on_every_port():
    assert source_from_text("/dev/pts/5") == "grbl:/dev/pts/5" and source_from_text("manual") == "manual"
    assert source_from_text("hello") is None
    choices = stage_choices(["/dev/ttyUSB0"], [("/dev/serial/by-id/usb-x", "/dev/ttyUSB0")], [("/dev/pts/9", "grbl")])
    sources = [src for _, src in choices]
    assert sources[:3] == ["sim", "emulator", "manual"]
    serial = [k for k in KINDS if k.serial]
    for k in serial:
        assert f"{k.scheme}/dev/ttyUSB0" in sources and f"{k.scheme}/dev/serial/by-id/usb-x" in sources
    assert sources.count("grbl:/dev/pts/9") == 1 and "emulator" in dict((s, l) for l, s in choices)["grbl:/dev/pts/9"]
    bare = [src for _, src in stage_choices([], [], [("/dev/pts/7", "")])]  # announced without a kind: a bare port
    assert bare[-1] == source_from_text("/dev/pts/7") == "grbl:/dev/pts/7"


def test_grbl_keeps_every_capability_and_the_simple_stages_declare_only_theirs():
    assert set(declared(GrblStage.__new__(GrblStage))) == {
        "settings", "console", "work coordinates", "jogging", "feed hold", "alarms"}
    sim = SimulatedStage()
    assert isinstance(sim, (Settings, WorkCoordinates, Jogging, FeedHold, Alarms)) and not isinstance(sim, Console)
    manual = open_stage("manual")
    command = open_stage("command:true {mm}")
    assert declared(manual) == ["operator moved"] and isinstance(manual, OperatorMoved)
    assert declared(command) == [] and isinstance(command, Stage) and command.connected
    assert not manual.can_home and not command.can_home
    from lps_gui.errors import HardwareError

    with pytest.raises(HardwareError, match="cannot home"):
        command.home()


@pytest.mark.parametrize("kind,spec_tail", [("zaber", ":1:1"), ("thorlabs", "")])
def test_the_vendor_stages_open_from_their_spec_and_declare_their_capabilities(kind, spec_tail):
    """zaber:PORT[:DEVICE[:AXIS]] and thorlabs:PORT through the registry, against their emulators (SPEC 16)."""
    emulator_class = emulated_kinds()[kind].emulator()
    with emulator_class(SimulatedStage()) as emu:
        stage = open_stage(f"{kind}:{emu.path}{spec_tail}")
        try:
            assert isinstance(stage, Settings) and isinstance(stage, Jogging) and isinstance(stage, FeedHold)
            assert {"settings", "feed hold"} <= set(declared(stage))
            assert not isinstance(stage, (Alarms, Console, WorkCoordinates, OperatorMoved))
            stage.home()
            stage.wait_idle(30.0)
            stage.move_to(2.0, 600.0)
            stage.wait_idle(30.0)
            assert abs(stage.position_mm() - 2.0) < 1e-3
        finally:
            stage.disconnect()


def test_a_zaber_spec_names_device_and_axis_after_the_port():
    from lps_gui.hardware.registry import kind_of as kind

    opened = {}

    class Recorder:
        def __init__(self, port, device=1, axis_number=1, **options):
            opened.update(port=port, device=device, axis=axis_number)

    import lps_gui.hardware.zaber as zaber_module
    real = zaber_module.ZaberStage
    zaber_module.ZaberStage = Recorder
    try:
        factory = kind("zaber:/dev/ttyUSB0").driver()
        factory("/dev/ttyUSB0:2:3")
        assert opened == {"port": "/dev/ttyUSB0", "device": 2, "axis": 3}
        factory("/dev/ttyUSB0:4")
        assert opened == {"port": "/dev/ttyUSB0", "device": 4, "axis": 1}
        factory("COM3")
        assert opened == {"port": "COM3", "device": 1, "axis": 1}
    finally:
        zaber_module.ZaberStage = real
