"""GRBL 1.1 codes in one table: error codes, alarm codes and settings with names, units, meanings.

Texts are GRBL's own (gnea/grbl ``doc/csv/{error,alarm,setting}_codes_en_US.csv``),
so a message a user sees names the same thing GRBL's documentation does. The
driver, the emulator and the simulated stage all look codes up here and
nowhere else (one table, like PyMeasure's ESP300 error mapping). The simulated
stage speaks neutral reasons (``hardware/refusals.py``); :func:`as_grbl` says
them as GRBL does, and a :class:`GrblError` names its neutral reason back.
"""
from __future__ import annotations

from typing import NamedTuple

from lps_gui.errors import HardwareError
from lps_gui.hardware.refusals import Alarm, Refusal, StageAlarm, StageRefused


class Code(NamedTuple):
    """An ``error:N`` or ``ALARM:N`` code: short name (v1.0 message) and description."""

    number: int
    name: str
    description: str


class Setting(NamedTuple):
    """A ``$N`` setting: name, unit, description and the default our emulator starts from."""

    number: int
    name: str
    unit: str
    description: str
    default: float


ERRORS: dict[int, Code] = {c.number: c for c in (
    Code(1, "Expected command letter", "G-code words consist of a letter and a value. Letter was not found."),
    Code(2, "Bad number format", "Missing the expected G-code word value or numeric value format is not valid."),
    Code(3, "Invalid statement", "Grbl '$' system command was not recognized or supported."),
    Code(4, "Value < 0", "Negative value received for an expected positive value."),
    Code(5, "Setting disabled", "Homing cycle failure. Homing is not enabled via settings."),
    Code(6, "Value < 3 usec", "Minimum step pulse time must be greater than 3usec."),
    Code(7, "EEPROM read fail. Using defaults", "An EEPROM read failed. Auto-restoring affected EEPROM to default values."),
    Code(8, "Not idle", "Grbl '$' command cannot be used unless Grbl is IDLE. Ensures smooth operation during a job."),
    Code(9, "G-code lock", "G-code commands are locked out during alarm or jog state."),
    Code(10, "Homing not enabled", "Soft limits cannot be enabled without homing also enabled."),
    Code(11, "Line overflow", "Max characters per line exceeded. Received command line was not executed."),
    Code(12, "Step rate > 30kHz", "Grbl '$' setting value cause the step rate to exceed the maximum supported."),
    Code(13, "Check Door", "Safety door detected as opened and door state initiated."),
    Code(14, "Line length exceeded", "Build info or startup line exceeded EEPROM line length limit. Line not stored."),
    Code(15, "Travel exceeded", "Jog target exceeds machine travel. Jog command has been ignored."),
    Code(16, "Invalid jog command", "Jog command has no '=' or contains prohibited g-code."),
    Code(17, "Setting disabled", "Laser mode requires PWM output."),
    Code(20, "Unsupported command", "Unsupported or invalid g-code command found in block."),
    Code(21, "Modal group violation", "More than one g-code command from same modal group found in block."),
    Code(22, "Undefined feed rate", "Feed rate has not yet been set or is undefined."),
    Code(23, "Invalid gcode ID:23", "G-code command in block requires an integer value."),
    Code(24, "Invalid gcode ID:24", "More than one g-code command that requires axis words found in block."),
    Code(25, "Invalid gcode ID:25", "Repeated g-code word found in block."),
    Code(26, "Invalid gcode ID:26", "No axis words found in block for g-code command or current modal state which requires them."),
    Code(27, "Invalid gcode ID:27", "Line number value is invalid."),
    Code(28, "Invalid gcode ID:28", "G-code command is missing a required value word."),
    Code(29, "Invalid gcode ID:29", "G59.x work coordinate systems are not supported."),
    Code(30, "Invalid gcode ID:30", "G53 only allowed with G0 and G1 motion modes."),
    Code(31, "Invalid gcode ID:31", "Axis words found in block when no command or current modal state uses them."),
    Code(32, "Invalid gcode ID:32", "G2 and G3 arcs require at least one in-plane axis word."),
    Code(33, "Invalid gcode ID:33", "Motion command target is invalid."),
    Code(34, "Invalid gcode ID:34", "Arc radius value is invalid."),
    Code(35, "Invalid gcode ID:35", "G2 and G3 arcs require at least one in-plane offset word."),
    Code(36, "Invalid gcode ID:36", "Unused value words found in block."),
    Code(37, "Invalid gcode ID:37", "G43.1 dynamic tool length offset is not assigned to configured tool length axis."),
    Code(38, "Invalid gcode ID:38", "Tool number greater than max supported value."),
)}

ALARMS: dict[int, Code] = {c.number: c for c in (
    Code(1, "Hard limit", "Hard limit has been triggered. Machine position is likely lost due to sudden halt. Re-homing is highly recommended."),
    Code(2, "Soft limit", "Soft limit alarm. G-code motion target exceeds machine travel. Machine position retained. Alarm may be safely unlocked."),
    Code(3, "Abort during cycle", "Reset while in motion. Machine position is likely lost due to sudden halt. Re-homing is highly recommended."),
    Code(4, "Probe fail", "Probe fail. Probe is not in the expected initial state before starting probe cycle when G38.2 and G38.3 is not triggered and G38.4 and G38.5 is triggered."),
    Code(5, "Probe fail", "Probe fail. Probe did not contact the workpiece within the programmed travel for G38.2 and G38.4."),
    Code(6, "Homing fail", "Homing fail. The active homing cycle was reset."),
    Code(7, "Homing fail", "Homing fail. Safety door was opened during homing cycle."),
    Code(8, "Homing fail", "Homing fail. Pull off travel failed to clear limit switch. Try increasing pull-off setting or check wiring."),
    Code(9, "Homing fail", "Homing fail. Could not find limit switch within search distances. Try increasing max travel, decreasing pull-off distance, or check wiring."),
    Code(10, "Homing fail", "Homing fail. On dual axis machines, could not find the second limit switch for self-squaring."),
)}

_S = Setting
SETTINGS: dict[int, Setting] = {s.number: s for s in (
    _S(0, "Step pulse time", "microseconds", "Sets time length per step. Minimum 3usec.", 10),
    _S(1, "Step idle delay", "milliseconds", "Sets a short hold delay when stopping to let dynamics settle before disabling steppers. Value 255 keeps motors enabled with no delay.", 25),
    _S(2, "Step pulse invert", "mask", "Inverts the step signal. Set axis bit to invert (00000ZYX).", 0),
    _S(3, "Step direction invert", "mask", "Inverts the direction signal. Set axis bit to invert (00000ZYX).", 0),
    _S(4, "Invert step enable pin", "boolean", "Inverts the stepper driver enable pin signal.", 0),
    _S(5, "Invert limit pins", "boolean", "Inverts the all of the limit input pins.", 0),
    _S(6, "Invert probe pin", "boolean", "Inverts the probe input pin signal.", 0),
    _S(10, "Status report options", "mask", "Alters data included in status reports.", 1),
    _S(11, "Junction deviation", "millimeters", "Sets how fast Grbl travels through consecutive motions. Lower value slows it down.", 0.010),
    _S(12, "Arc tolerance", "millimeters", "Sets the G2 and G3 arc tracing accuracy based on radial error. Beware: A very small value may effect performance.", 0.002),
    _S(13, "Report in inches", "boolean", "Enables inch units when returning any position and rate value that is not a settings value.", 0),
    _S(20, "Soft limits enable", "boolean", "Enables soft limits checks within machine travel and sets alarm when exceeded. Requires homing.", 0),
    _S(21, "Hard limits enable", "boolean", "Enables hard limits. Immediately halts motion and throws an alarm when switch is triggered.", 0),
    _S(22, "Homing cycle enable", "boolean", "Enables homing cycle. Requires limit switches on all axes.", 0),
    _S(23, "Homing direction invert", "mask", "Homing searches for a switch in the positive direction. Set axis bit (00000ZYX) to search in negative direction.", 0),
    _S(24, "Homing locate feed rate", "mm/min", "Feed rate to slowly engage limit switch to determine its location accurately.", 25.0),
    _S(25, "Homing search seek rate", "mm/min", "Seek rate to quickly find the limit switch before the slower locating phase.", 500.0),
    _S(26, "Homing switch debounce delay", "milliseconds", "Sets a short delay between phases of homing cycle to let a switch debounce.", 250),
    _S(27, "Homing switch pull-off distance", "millimeters", "Retract distance after triggering switch to disengage it. Homing will fail if switch isn't cleared.", 1.0),
    _S(30, "Maximum spindle speed", "RPM", "Maximum spindle speed. Sets PWM to 100% duty cycle.", 1000),
    _S(31, "Minimum spindle speed", "RPM", "Minimum spindle speed. Sets PWM to 0.4% or lowest duty cycle.", 0),
    _S(32, "Laser-mode enable", "boolean", "Enables laser mode. Consecutive G1/2/3 commands will not halt when spindle speed is changed.", 0),
    *[_S(100 + i, f"{a}-axis travel resolution", "step/mm", f"{a}-axis travel resolution in steps per millimeter.", 250.0) for i, a in enumerate("XYZ")],
    *[_S(110 + i, f"{a}-axis maximum rate", "mm/min", f"{a}-axis maximum rate. Used as G0 rapid rate.", 500.0) for i, a in enumerate("XYZ")],
    *[_S(120 + i, f"{a}-axis acceleration", "mm/sec^2", f"{a}-axis acceleration. Used for motion planning to not exceed motor torque and lose steps.", 10.0) for i, a in enumerate("XYZ")],
    *[_S(130 + i, f"{a}-axis maximum travel", "millimeters", f"Maximum {a}-axis travel distance from homing switch. Determines valid machine space for soft-limits and homing search distances.", 200.0) for i, a in enumerate("XYZ")],
)}

# settings printed as integers by $$ (GRBL prints masks, booleans, ms and us without decimals)
INTEGER_SETTINGS = frozenset({0, 1, 2, 3, 4, 5, 6, 10, 13, 20, 21, 22, 23, 26, 30, 31, 32})
# defaults.h DEFAULTS_GENERIC (config.h's choice): what settings.c settings_restore() writes for '$RST=$' and '$RST=*'
DEFAULT_SETTINGS: dict[int, float] = {
    0: 10.0, 1: 25.0, 2: 0.0, 3: 0.0, 4: 0.0, 5: 0.0, 6: 0.0, 10: 1.0, 11: 0.010, 12: 0.002, 13: 0.0,
    20: 0.0, 21: 0.0, 22: 0.0, 23: 0.0, 24: 25.0, 25: 500.0, 26: 250.0, 27: 1.0, 30: 1000.0, 31: 0.0, 32: 0.0,
    **{100 + i: 250.0 for i in range(3)}, **{110 + i: 500.0 for i in range(3)},
    **{120 + i: 10.0 for i in range(3)}, **{130 + i: 200.0 for i in range(3)},
}
STATUS_MASK_MPOS = 1  # $10 bit 0: report MPos (else WPos)
STATUS_MASK_BUFFER = 2  # $10 bit 1: report Bf:planner,rx


def error_text(code: int) -> str:
    """``"error:15 Travel exceeded: Jog target exceeds ..."`` for any code, known or not."""
    c = ERRORS.get(code)
    return f"error:{code} {c.name}: {c.description}" if c else f"error:{code} (unknown GRBL error code)"


def alarm_text(code: int) -> str:
    """``"ALARM:1 Hard limit: Hard limit has been triggered..."`` for any code, known or not."""
    c = ALARMS.get(code)
    return f"ALARM:{code} {c.name}: {c.description}" if c else f"ALARM:{code} (unknown GRBL alarm code)"


def setting_info(number: int) -> Setting:
    """The table entry for ``$number``; unknown numbers get a placeholder name (firmware forks add some)."""
    return SETTINGS.get(number) or Setting(number, f"${number}", "", "setting not in the GRBL 1.1 table", 0.0)


def format_setting(number: int, value: float) -> str:
    """``$N=value`` as GRBL prints it in ``$$`` (3 decimals for floats, none for integers)."""
    return f"${number}={int(round(value))}" if number in INTEGER_SETTINGS else f"${number}={value:.3f}"


BOOLEAN_SETTINGS = frozenset({4, 5, 6, 13, 20, 21, 22, 32})  # settings.c stores them as flags: any non-zero is 1


def check_setting(settings: dict[int, float], number: int, value: float) -> None:
    """Raise GrblError like settings.c ``settings_store_global_setting`` would for ``$number=value``.

    Negative: error:4 (checked first); unknown number: error:3; ``$0`` below
    3 us: error:6; soft limits without homing: error:10. The step-rate check
    (error:12) is compiled only with MAX_STEP_RATE_HZ, which stock config.h
    leaves commented out, so ``$110=100000`` is accepted like on the firmware.
    """
    context = f"${number}={value:g}"
    if value < 0:
        raise GrblError("error", 4, context)
    if number not in SETTINGS:
        raise GrblError("error", 3, context)
    if number == 0 and int(value) < 3:
        raise GrblError("error", 6, context)
    if number == 20 and int(value) and not settings.get(22):
        raise GrblError("error", 10, context)


def stored_settings(number: int, value: float) -> dict[int, float]:
    """What settings.c stores for an accepted ``$number=value``: the value and the settings it forces.

    Integer settings keep ``trunc(value)``, flags 0 or 1; ``$22=0`` also clears
    ``$20`` ("Force disable soft-limits"). The emulator's stage and the
    driver's cache both apply this, so they agree with the firmware.
    """
    if number in BOOLEAN_SETTINGS:
        value = float(bool(int(value)))
    elif number in INTEGER_SETTINGS - {30, 31}:  # $30/$31 are floats printed without decimals
        value = float(int(value))
    out = {number: float(value)}
    if number == 22 and not value:
        out[20] = 0.0
    return out


ALARM_NUMBERS: dict[Alarm, int] = {
    Alarm.LOCK: 0, Alarm.HARD_LIMIT: 1, Alarm.SOFT_LIMIT: 2, Alarm.ABORT_DURING_CYCLE: 3, Alarm.PROBE_FAIL_INITIAL: 4,
    Alarm.PROBE_FAIL_CONTACT: 5, Alarm.HOMING_RESET: 6, Alarm.HOMING_DOOR: 7, Alarm.HOMING_PULLOFF: 8,
    Alarm.HOMING_NOT_FOUND: 9, Alarm.HOMING_DUAL: 10,
}  # 0: GRBL's silent homing lock (no ALARM:N line)
ALARM_REASONS: dict[int, Alarm] = {n: a for a, n in ALARM_NUMBERS.items()}
ERROR_CODES: dict[Refusal, int] = {
    Refusal.UNKNOWN_AXIS: 20, Refusal.UNKNOWN_WORK_SYSTEM: 20, Refusal.LOCKED: 9, Refusal.NOT_IDLE: 8,
    Refusal.NO_FEED: 22, Refusal.BEYOND_TRAVEL: 15, Refusal.HOMING_DISABLED: 5, Refusal.NEGATIVE_VALUE: 4,
    Refusal.UNKNOWN_SETTING: 3, Refusal.SOFT_LIMITS_NEED_HOMING: 10,
}
REFUSALS: dict[int, Refusal] = {n: r for r, n in ERROR_CODES.items() if n != 20}  # error:20 is any unsupported word


def alarm_number(alarm: Alarm | None) -> int | None:
    """GRBL's ``ALARM:N`` number of a neutral alarm (0: the homing lock), None for none."""
    return None if alarm is None else ALARM_NUMBERS[alarm]


def as_grbl(e: StageRefused | StageAlarm) -> GrblError:
    """The simulated stage's refusal or alarm as GRBL reports it (``error:N``, ``ALARM:N``)."""
    if isinstance(e, StageAlarm):
        return GrblError("alarm", ALARM_NUMBERS[e.alarm])
    return GrblError("error", ERROR_CODES[e.reason])


class GrblError(HardwareError):
    """GRBL answered ``error:N`` or raised ``ALARM:N``; ``kind`` and ``code`` say which, ``reason`` the
    neutral :class:`~lps_gui.hardware.refusals.Refusal` or :class:`~lps_gui.hardware.refusals.Alarm` (None:
    GRBL-only, e.g. a G-code word it does not know)."""

    def __init__(self, kind: str, code: int, context: str = "") -> None:
        self.kind = kind  # "error" or "alarm"
        self.code = code
        self.reason: Refusal | Alarm | None = (ALARM_REASONS if kind == "alarm" else REFUSALS).get(code)
        text = error_text(code) if kind == "error" else alarm_text(code)
        hint = _HINTS.get((kind, code), "")
        super().__init__(f"{context}{': ' if context else ''}{text}{hint}")


_HINTS = {
    ("alarm", 1): " Reset the controller, then home ($H) before measuring.",
    ("alarm", 2): " Reset the controller, then unlock ($X).",
    ("alarm", 3): " Unlock ($X) or home ($H) to continue.",
    ("error", 9): " Unlock ($X) or home ($H) first.",
    ("error", 15): " Choose a target inside the travel.",
}


def travel_text(values: dict[int, float]) -> str:
    """The soft-limit travel of each axis from $20 and $130-$132 (GRBL's machine space: -$13x .. 0 after homing)."""
    spans = [f"{ax} {values[130 + i]:g} mm" for i, ax in enumerate("XYZ") if 130 + i in values]
    if not spans:
        return "travel: unknown"
    limits = "soft limits ON" if values.get(20) else "soft limits off ($20=0): nothing stops a move past the ends"
    return f"travel {', '.join(spans)}; {limits}"
