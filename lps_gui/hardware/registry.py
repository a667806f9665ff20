"""Every kind of stage in one table: its source scheme, its driver, its ports, its emulator and its help.

The CLI (``lps capture --stage``, ``lps emulate KIND``), the GUI's source list
and :func:`lps_gui.hardware.open_stage` read :data:`KINDS` and nothing else,
so a new stage is one driver file, one emulator file, one test file and one
entry here (docs/hardware.md). Each entry's loader imports its driver (and
emulator) only when used: listing the kinds costs nothing.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from lps_gui.errors import InputError


@dataclass(frozen=True)
class StageKind:
    """One kind of stage.

    scheme : "grbl:" (the source names a port or an argument after it) or "sim" (a bare word).
    name : short name (``lps emulate NAME``, port listings).
    driver : returns the callable making the stage from (argument, **options); a bare word's takes no argument.
    help : the source's syntax and one line on it, for ``--help`` and the GUI's tooltip.
    serial : the argument is a serial port: the GUI lists the ports for it and a bare port is offered as it.
    emulator : returns its emulator class (``lps emulate NAME``), or None.
    connects : the driver returns a connected stage (an emulator it starts itself).
    """

    scheme: str
    name: str
    driver: Callable[[], Callable[..., Any]]
    help: str
    serial: bool = False
    emulator: Callable[[], type] | None = None
    connects: bool = False

    @property
    def takes_argument(self) -> bool:
        return self.scheme.endswith(":")

    def matches(self, spec: str) -> bool:
        return spec.startswith(self.scheme) and len(spec) > len(self.scheme) if self.takes_argument else spec == self.scheme

    def build(self, spec: str, **options: Any):
        """The stage of ``spec``, not yet connected unless its driver connects itself (``connects``): for a caller
        that connects it on its own thread (the GUI's stage thread), since a port opened twice is refused by
        some vendors' libraries (zaber-motion: "port is likely already opened")."""
        factory = self.driver()
        return factory(spec[len(self.scheme):], **options) if self.takes_argument else factory(**options)

    def make(self, spec: str, **options: Any):
        """The (connected) stage of ``spec``."""
        stage = self.build(spec, **options)
        if not self.connects:
            stage.connect()
        return stage


def _sim():
    from lps_gui.hardware.sim_stage import SimulatedStage
    return SimulatedStage


def _grbl_emulated():
    from lps_gui.hardware.grbl.emulator import emulated_grbl_stage
    return emulated_grbl_stage


def _grbl():
    from lps_gui.hardware.grbl.driver import GrblStage
    return GrblStage


def _grbl_emulator():
    from lps_gui.hardware.grbl.emulator import GrblEmulator
    return GrblEmulator


def _marlin():
    from lps_gui.hardware.marlin.driver import MarlinStage
    return MarlinStage


def _marlin_emulator():
    from lps_gui.hardware.marlin.emulator import MarlinEmulator
    return MarlinEmulator


def _zaber():
    from lps_gui.hardware.zaber import ZaberStage

    def open_zaber(argument: str, **options: Any) -> Any:
        """zaber:PORT[:DEVICE[:AXIS]] (SPEC 16): device and axis numbers after the port, 1 and 1 by default."""
        parts = argument.split(":")
        numbers = []
        while len(parts) > 1 and parts[-1].isdigit() and len(numbers) < 2:
            numbers.insert(0, int(parts.pop()))
        device, axis = (numbers + [1, 1])[:2] if len(numbers) < 2 else numbers
        return ZaberStage(":".join(parts), device=device, axis_number=axis, **options)
    return open_zaber


def _zaber_emulator():
    from lps_gui.hardware.zaber_emulator import ZaberEmulator
    return ZaberEmulator


def _thorlabs():
    from lps_gui.hardware.thorlabs import ThorlabsStage
    return ThorlabsStage


def _thorlabs_emulator():
    from lps_gui.hardware.thorlabs_emulator import ThorlabsEmulator
    return ThorlabsEmulator


def _manual():
    from lps_gui.hardware.manual import ManualStage
    return ManualStage


def _command():
    from lps_gui.hardware.command import CommandStage
    return CommandStage


KINDS: tuple[StageKind, ...] = (
    StageKind("sim", "sim", _sim, "sim: simulated stage"),
    # "emulator" is the word users type for the emulated rig (lps capture --stage emulator, the GUI's source list,
    # open_stage("emulator"); docs/capture.md): GRBL's driver on GRBL's emulator, said here and nowhere else. Another
    # protocol's emulated rig is `lps emulate KIND` and its KIND:PATH.
    StageKind("emulator", "emulator", _grbl_emulated, "emulator: GRBL emulator (pty)", connects=True),
    StageKind("grbl:", "grbl", _grbl, "grbl:PORT: GRBL 1.1 (e.g. grbl:/dev/ttyUSB0, grbl:COM3)", serial=True, emulator=_grbl_emulator),
    StageKind("marlin:", "marlin", _marlin, "marlin:PORT: Marlin 2.x G-code (e.g. marlin:/dev/ttyACM0)", serial=True, emulator=_marlin_emulator),
    StageKind("zaber:", "zaber", _zaber, "zaber:PORT[:DEVICE[:AXIS]]: Zaber ASCII through zaber-motion (device 1, axis 1 by default)",
              serial=True, emulator=_zaber_emulator),
    StageKind("thorlabs:", "thorlabs", _thorlabs, "thorlabs:PORT: Thorlabs KDC101 + MTS/Z8 stage (APT)", serial=True,
              emulator=_thorlabs_emulator),
    StageKind("manual", "manual", _manual, "manual: manual stage (you move it and confirm each stop)"),
    StageKind("command:", "command", _command, "command:'./move.sh {mm}': a program moves the stage, one run per move"),
)

DEFAULT_PORT_KIND = "grbl:"  # what a bare port typed into the GUI opens as


def kind_of(spec: str) -> StageKind:
    """The kind whose scheme ``spec`` has; InputError listing every kind otherwise."""
    spec = (spec or "").strip()
    for kind in KINDS:
        if kind.matches(spec):
            return kind
    raise InputError(f"stage {spec!r}: not understood; use {specs_help()}")


def specs_help() -> str:
    """Every source's syntax, for ``--stage``'s help and error messages."""
    return " | ".join(k.help.split(": ", 1)[0] for k in KINDS)


def emulated_kinds() -> dict[str, StageKind]:
    """The kinds ``lps emulate`` serves, by name."""
    return {k.name: k for k in KINDS if k.emulator}


def source_from_text(text: str) -> str | None:
    """A source typed by the operator: a spec of a kind, or a bare port (opened as :data:`DEFAULT_PORT_KIND`)."""
    text = text.strip()
    if any(k.matches(text) for k in KINDS):
        return text
    if text.startswith(("/dev/", "COM", "socket://", "rfc2217://", "loop://")):
        return f"{DEFAULT_PORT_KIND}{text}"
    return None


def stage_choices(ports: list[str], by_id: list[tuple[str, str]], announced: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """(label, source) of every kind: the bare words, then each serial kind on every port found.

    ``ports``: device names; ``by_id``: (stable link, device); ``announced``: (port, kind name) of running emulators
    (a port announced without a kind is a bare port: :data:`DEFAULT_PORT_KIND`, as typed).
    """
    out = [(k.help.split(": ", 1)[1][:1].upper() + k.help.split(": ", 1)[1][1:], k.scheme) for k in KINDS if not k.takes_argument]
    serial = [k for k in KINDS if k.serial]
    for k in serial:
        out += [(f"{p} ({k.name})", f"{k.scheme}{p}") for p in ports]
        out += [(f"{link} ({device.rsplit('/', 1)[-1]}, {k.name})", f"{k.scheme}{link}") for link, device in by_id]
    listed = {src for _, src in out}
    names = {k.name: k for k in serial}
    bare = next(k for k in serial if k.scheme == DEFAULT_PORT_KIND)
    for port, name in announced:
        k = names.get(name) if name else bare
        if k is not None and f"{k.scheme}{port}" not in listed:
            out.append((f"{port} ({k.name} emulator)", f"{k.scheme}{port}"))
    return out
