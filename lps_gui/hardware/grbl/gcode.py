"""G-code blocks checked the way GRBL 1.1h's ``gc_execute_line()`` (gcode.c) checks them.

Lines arrive pre-filtered as GRBL's protocol loop leaves them (no spaces, no
comments, upper case, see :func:`clean_line`). :func:`check_block` follows
gcode.c's steps 1-3 in their order, so the first error GRBL finds is the one
raised: step 2 reads the words (errors 1, 2, 20, 23, 24, 21, 38, 25, 4 as each
word arrives), step 3 checks the block against the parser state (27, 22, 28,
37, 26, 29, 30, 31, 32-35, 36) and pre-computes the targets in machine
coordinates (work coordinate system, G92 offset, G53, G91, inches). The
firmware then executes the :class:`Block` (gcode.c step 4) on its
:class:`ParserState`. Jog lines (``$J=``) take the same path with G1/G94
enforced; the jog-only rules of step 4 (error 16) are in :meth:`Block.check_jog`.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

NUMBER_RE = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)")  # nuts_bolts.c read_float(): sign, digits, one '.'
LINE_BUFFER_SIZE = 80  # GRBL's LINE_BUFFER_SIZE: longer lines answer error:11
MM_PER_INCH = 25.4
MAX_LINE_NUMBER = 10000000
MAX_TOOL_NUMBER = 255
N_COORDINATE_SYSTEM = 6  # G54-G59; stored coordinates 6 and 7 are G28 and G30
Z = 2  # config.h TOOL_LENGTH_OFFSET_AXIS

# axis_command of gcode.c
AXIS_NONE, AXIS_NON_MODAL, AXIS_MOTION, AXIS_TLO = 0, 1, 2, 3
# non-modal commands (gcode.h numbering: G28.1 = 38, G30.1 = 40, G92.1 = 102)
DWELL, SET_COORD_DATA, GO_HOME_0, SET_HOME_0, GO_HOME_1, SET_HOME_1, ABSOLUTE_OVERRIDE, SET_OFFSET, RESET_OFFSET = (
    4, 10, 28, 38, 30, 40, 53, 92, 102)
# motion modes (gcode.h: G38.2-G38.5 = 140-143, G80 = 80)
SEEK, LINEAR, CW_ARC, CCW_ARC, MOTION_NONE = 0, 1, 2, 3, 80
PROBE_MODES = (140, 141, 142, 143)
# modal groups (gcode.h)
G0_GROUP, G1_GROUP, G2_GROUP, G3_GROUP, G4_GROUP, G5_GROUP, G6_GROUP, G7_GROUP, G8_GROUP, G12_GROUP, G13_GROUP = (
    "G0", "G1", "G2", "G3", "G4", "G5", "G6", "G7", "G8", "G12", "G13")
M4_GROUP, M7_GROUP, M8_GROUP = "M4", "M7", "M8"
PLANES = {0: (0, 1, 2), 1: (2, 0, 1), 2: (1, 2, 0)}  # G17 XY, G18 ZX, G19 YZ: (axis_0, axis_1, linear)


class CodeError(Exception):
    """A GRBL ``error:N`` found while checking a line."""

    def __init__(self, code: int) -> None:
        super().__init__(code)
        self.code = code


@dataclass
class Modal:
    """gcode.h ``gc_modal_t``: the modal state ``$G`` reports."""

    motion: int = SEEK
    feed_mode: int = 94  # G93 / G94
    units: int = 21  # G20 / G21
    distance: int = 90  # G90 / G91
    plane: int = 0  # 0 G17, 1 G18, 2 G19
    coord_select: int = 0  # 0-5: G54-G59
    tool_length: str = "G49"  # "G49" or "G43.1"
    program_flow: int = 0  # 0 running, 3 paused (M0), 2 / 30 program end
    spindle: int = 5  # M3 / M4 / M5
    coolant: int = 9  # M8 / M9 (M7 is not compiled in stock 1.1h)


@dataclass
class ParserState:
    """gcode.h ``parser_state_t``: what gc_init() clears at every reset (machine mm)."""

    modal: Modal = field(default_factory=Modal)
    spindle_speed: float = 0.0
    feed_rate: float = 0.0
    tool: int = 0
    position: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # where the parser thinks it is
    coord_system: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # the active G54-G59 offset
    coord_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # G92
    tool_length_offset: float = 0.0

    def wco(self) -> tuple[float, float, float]:
        """report.c: WCO = coordinate system + G92 offset (+ tool length offset on Z)."""
        out = [c + o for c, o in zip(self.coord_system, self.coord_offset)]
        out[Z] += self.tool_length_offset
        return tuple(out)  # type: ignore[return-value]


@dataclass
class Block:
    """A block that passed the checks: its new modal state, commands and pre-computed values."""

    modal: Modal
    groups: set[str]
    non_modal: int = 0
    axis_command: int = AXIS_NONE
    axis_words: dict[int, float] = field(default_factory=dict)  # as written (mm after G20 conversion)
    xyz: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # machine target (G92: the new offset)
    ijk: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # arc offsets, G10 / G28 / G30 data
    block_coord_system: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    coord_index: int = 0  # G10: the stored system it writes
    f: float = 0.0
    s: float = 0.0
    t: int = 0
    p: float = 0.0
    r: float = 0.0
    words: dict[str, float] = field(default_factory=dict)  # every value word, as read

    def check_jog(self) -> None:
        """gcode.c step 4 for ``$J=``: only G20/G21, G90/G91 and G53 may appear (error:16)."""
        if self.groups - {G3_GROUP, G6_GROUP, G0_GROUP}:
            raise CodeError(16)
        if self.non_modal not in (ABSOLUTE_OVERRIDE, 0):
            raise CodeError(16)


def clean_line(raw: str) -> tuple[str, bool]:
    """Filter a received line like protocol.c: drop whitespace/control chars, comments, '/'; upcase.

    Returns the cleaned line and whether it overflowed the line buffer.
    """
    out: list[str] = []
    comment = ""
    overflow = False
    for c in raw:
        if comment:
            if c == ")" and comment == "(":
                comment = ""
            continue
        if c <= " " or c == "/":
            continue
        if c in "(;":
            comment = c
            continue
        if len(out) >= LINE_BUFFER_SIZE - 1:
            overflow = True
            continue
        out.append(c.upper())
    return "".join(out), overflow


def read_float(text: str, i: int) -> tuple[float, int] | None:
    """nuts_bolts.c read_float(): the number at ``text[i]`` and the index after it, None if there is none."""
    m = NUMBER_RE.match(text, i)
    return (float(m.group()), m.end()) if m else None


def _g_word(block: Block, int_value: int, mantissa: int, axis_command: int) -> tuple[str, int, int]:
    """One G word (gcode.c step 2): its modal group, the axis command it claims, the mantissa left."""
    if int_value in (10, 28, 30, 92, 4, 53):
        if int_value in (10, 28, 30, 92) and mantissa == 0:
            if axis_command:
                raise CodeError(24)
            axis_command = AXIS_NON_MODAL
        block.non_modal = int_value
        if int_value in (28, 30, 92):
            if mantissa not in (0, 10):
                raise CodeError(20)
            block.non_modal += mantissa
            mantissa = 0
        return G0_GROUP, axis_command, mantissa
    if int_value in (0, 1, 2, 3, 38, 80):
        if int_value != 80:
            if axis_command:
                raise CodeError(24)
            axis_command = AXIS_MOTION
        block.modal.motion = int_value
        if int_value == 38:
            if mantissa not in (20, 30, 40, 50):
                raise CodeError(20)
            block.modal.motion = 100 + 38 + mantissa // 10
            mantissa = 0
        return G1_GROUP, axis_command, mantissa
    if int_value in (17, 18, 19):
        block.modal.plane = int_value - 17
        return G2_GROUP, axis_command, mantissa
    if int_value in (90, 91):
        if mantissa == 0:
            block.modal.distance = int_value
            return G3_GROUP, axis_command, mantissa
        if mantissa != 10 or int_value == 90:
            raise CodeError(20)  # G90.1 is not supported; G91.1 does nothing
        return G4_GROUP, axis_command, 0
    if int_value in (93, 94):
        block.modal.feed_mode = int_value
        return G5_GROUP, axis_command, mantissa
    if int_value in (20, 21):
        block.modal.units = int_value
        return G6_GROUP, axis_command, mantissa
    if int_value == 40:
        return G7_GROUP, axis_command, mantissa
    if int_value in (43, 49):
        if axis_command:
            raise CodeError(24)
        if int_value == 49:
            block.modal.tool_length = "G49"
        elif mantissa == 10:
            block.modal.tool_length = "G43.1"
        else:
            raise CodeError(20)
        return G8_GROUP, AXIS_TLO, 0
    if 54 <= int_value <= 59:
        block.modal.coord_select = int_value - 54
        return G12_GROUP, axis_command, mantissa
    if int_value == 61:
        if mantissa != 0:
            raise CodeError(20)
        return G13_GROUP, axis_command, mantissa
    raise CodeError(20)


def _m_word(block: Block, int_value: int) -> str:
    if int_value in (0, 1, 2, 30):
        if int_value == 0:
            block.modal.program_flow = 3
        elif int_value != 1:  # M1 (optional stop) is ignored
            block.modal.program_flow = int_value
        return M4_GROUP
    if int_value in (3, 4, 5):
        block.modal.spindle = int_value
        return M7_GROUP
    if int_value in (8, 9):
        block.modal.coolant = int_value
        return M8_GROUP
    raise CodeError(20)


def _read_words(text: str, block: Block, jog: bool) -> int:
    """gcode.c step 2: every word in order; returns the axis command the words claim."""
    axis_command = AXIS_NONE
    i = 0
    while i < len(text):
        letter = text[i]
        if not "A" <= letter <= "Z":
            raise CodeError(1)
        got = read_float(text, i + 1)
        if got is None:
            raise CodeError(2)
        value, i = got
        int_value = math.trunc(value)
        mantissa = round(100 * (value - int_value))
        if letter == "G":
            group, axis_command, mantissa = _g_word(block, int_value, mantissa, axis_command)
            if mantissa > 0:
                raise CodeError(23)
            if group in block.groups:
                raise CodeError(21)
            block.groups.add(group)
        elif letter == "M":
            if mantissa > 0:
                raise CodeError(23)
            group = _m_word(block, int_value)
            if group in block.groups:
                raise CodeError(21)
            block.groups.add(group)
        else:
            if letter not in "FIJKLNPRSTXYZ":
                raise CodeError(20)
            if letter == "T" and value > MAX_TOOL_NUMBER:
                raise CodeError(38)
            if letter in block.words:
                raise CodeError(25)
            if letter in "FNPTS" and value < 0:
                raise CodeError(4)
            block.words[letter] = float(int_value) if letter in "LNT" else value
    return axis_command


def check_block(text: str, state: ParserState, coords: list[list[float]], jog: bool = False) -> Block:
    """Check a cleaned block (for a jog, the part after ``$J=``) against ``state``; raise CodeError(N) like GRBL.

    ``coords`` are the stored coordinate data (machine mm): G54-G59, G28, G30.
    """
    block = Block(modal=replace(state.modal), groups=set())
    if jog:
        block.modal.motion, block.modal.feed_mode = LINEAR, 94
    axis_command = _read_words(text, block, jog)
    w = block.words
    block.axis_words = {"XYZ".index(k): v for k, v in w.items() if k in "XYZ"}
    axes = block.axis_words
    unused = set(w)
    if axes and not axis_command:
        axis_command = AXIS_MOTION  # implicit: the current motion mode
    if w.get("N", 0) > MAX_LINE_NUMBER:
        raise CodeError(27)
    inches = block.modal.units == 20
    block.f = w.get("F", 0.0)
    if jog:
        if "F" not in w:
            raise CodeError(22)
        block.f *= MM_PER_INCH if inches else 1.0
    elif block.modal.feed_mode == 93:
        if axis_command == AXIS_MOTION and block.modal.motion not in (MOTION_NONE, SEEK) and "F" not in w:
            raise CodeError(22)
    elif state.modal.feed_mode == 94:
        block.f = block.f * (MM_PER_INCH if inches else 1.0) if "F" in w else state.feed_rate
    block.s = w.get("S", state.spindle_speed)
    block.t = int(w.get("T", 0))
    block.p = w.get("P", 0.0)
    if block.non_modal == DWELL:
        if "P" not in w:
            raise CodeError(28)
        unused.discard("P")
    axis_0, axis_1, _ = PLANES[block.modal.plane]
    if inches:
        axes = block.axis_words = {i: v * MM_PER_INCH for i, v in axes.items()}
    if axis_command == AXIS_TLO and block.modal.tool_length == "G43.1" and set(axes) != {Z}:
        raise CodeError(37)
    block.block_coord_system = list(state.coord_system)
    if G12_GROUP in block.groups and state.modal.coord_select != block.modal.coord_select:
        block.block_coord_system = list(coords[block.modal.coord_select])
    xyz = block.xyz
    if block.non_modal == SET_COORD_DATA:
        if not axes:
            raise CodeError(26)
        if "P" not in w and "L" not in w:
            raise CodeError(28)
        p = math.trunc(block.p)
        if p > N_COORDINATE_SYSTEM:
            raise CodeError(29)
        l_word = w.get("L", 0)
        if l_word != 20 and (l_word != 2 or "R" in w):
            raise CodeError(20)
        unused -= {"L", "P"}
        block.coord_index = p - 1 if p > 0 else block.modal.coord_select
        block.ijk = list(coords[block.coord_index])
        for i, v in axes.items():
            if l_word == 20:
                block.ijk[i] = state.position[i] - state.coord_offset[i] - v - (state.tool_length_offset if i == Z else 0.0)
            else:
                block.ijk[i] = v
    elif block.non_modal == SET_OFFSET:
        if not axes:
            raise CodeError(26)
        for i in range(3):
            if i in axes:
                xyz[i] = state.position[i] - block.block_coord_system[i] - axes[i] - (state.tool_length_offset if i == Z else 0.0)
            else:
                xyz[i] = state.coord_offset[i]
    else:
        if axis_command != AXIS_TLO and axes:
            for i in range(3):
                if i not in axes:
                    xyz[i] = state.position[i]
                elif block.non_modal == ABSOLUTE_OVERRIDE:
                    xyz[i] = axes[i]
                elif block.modal.distance == 90:
                    xyz[i] = axes[i] + block.block_coord_system[i] + state.coord_offset[i] + (
                        state.tool_length_offset if i == Z else 0.0)
                else:
                    xyz[i] = axes[i] + state.position[i]
        elif axis_command == AXIS_TLO:
            for i, v in axes.items():
                xyz[i] = v
        if block.non_modal in (GO_HOME_0, GO_HOME_1):
            block.ijk = list(coords[6 if block.non_modal == GO_HOME_0 else 7])
            if axes:
                for i in range(3):
                    if i not in axes:
                        block.ijk[i] = state.position[i]
            else:
                axis_command = AXIS_NONE
        elif block.non_modal == ABSOLUTE_OVERRIDE and block.modal.motion not in (SEEK, LINEAR):
            raise CodeError(30)
    motion = block.modal.motion
    if motion == MOTION_NONE:
        if axes:
            raise CodeError(31)
    elif axis_command == AXIS_MOTION:
        if motion == SEEK:
            if not axes:
                axis_command = AXIS_NONE
        else:
            if block.f == 0.0:
                raise CodeError(22)
            if motion == LINEAR:
                if not axes:
                    axis_command = AXIS_NONE
            elif motion in (CW_ARC, CCW_ARC):
                _check_arc(block, state, axis_0, axis_1, unused, inches)
            elif motion in PROBE_MODES:
                if not axes:
                    raise CodeError(26)
                if xyz == state.position:
                    raise CodeError(33)
    unused -= {"N", "F"} if jog else {"N", "F", "S", "T"}
    if axis_command:
        unused -= set("XYZ")
    if unused:
        raise CodeError(36)
    block.axis_command = axis_command
    return block


def _check_arc(block: Block, state: ParserState, axis_0: int, axis_1: int, unused: set[str], inches: bool) -> None:
    """gcode.c's G2/G3 checks: axis words in the plane, then radius mode (R) or offset mode (IJK)."""
    axes, w, xyz = block.axis_words, block.words, block.xyz
    if not axes:
        raise CodeError(26)
    if axis_0 not in axes and axis_1 not in axes:
        raise CodeError(32)
    x = xyz[axis_0] - state.position[axis_0]
    y = xyz[axis_1] - state.position[axis_1]
    if "R" in w:
        unused.discard("R")
        if xyz == state.position:
            raise CodeError(33)
        r = w["R"] * (MM_PER_INCH if inches else 1.0)
        h = 4.0 * r * r - x * x - y * y
        if h < 0:
            raise CodeError(34)
        h = -math.sqrt(h) / math.hypot(x, y)
        if block.modal.motion == CCW_ARC:
            h = -h
        if r < 0:
            h, r = -h, -r
        block.ijk[axis_0] = 0.5 * (x - y * h)
        block.ijk[axis_1] = 0.5 * (y + x * h)
        block.r = r
        return
    letters = "IJK"
    if letters[axis_0] not in w and letters[axis_1] not in w:
        raise CodeError(35)
    unused -= set(letters)
    for i, k in enumerate(letters):
        if k in w:
            block.ijk[i] = w[k] * (MM_PER_INCH if inches else 1.0)
    target_r = math.hypot(x - block.ijk[axis_0], y - block.ijk[axis_1])
    block.r = math.hypot(block.ijk[axis_0], block.ijk[axis_1])
    delta_r = abs(target_r - block.r)
    if delta_r > 0.005 and (delta_r > 0.5 or delta_r > 0.001 * block.r):
        raise CodeError(33)


def arc_points(block: Block, position: list[float], arc_tolerance_mm: float) -> list[list[float]]:
    """The segment end points motion_control.c mc_arc() would plan (for soft-limit checks), target last."""
    axis_0, axis_1, linear = PLANES[block.modal.plane]
    c0, c1 = position[axis_0] + block.ijk[axis_0], position[axis_1] + block.ijk[axis_1]
    r0, r1 = -block.ijk[axis_0], -block.ijk[axis_1]
    t0, t1 = block.xyz[axis_0] - c0, block.xyz[axis_1] - c1
    travel = math.atan2(r0 * t1 - r1 * t0, r0 * t0 + r1 * t1)
    if block.modal.motion == CW_ARC:
        if travel >= -5e-7:
            travel -= 2 * math.pi
    elif travel <= 5e-7:
        travel += 2 * math.pi
    r, tol = block.r, arc_tolerance_mm
    segments = int(math.floor(abs(0.5 * travel * r) / math.sqrt(tol * (2 * r - tol)))) if 0 < tol < 2 * r else 0
    points = []
    for k in range(1, segments):
        a = travel * k / segments
        p = list(position)
        p[axis_0] = c0 + r0 * math.cos(a) - r1 * math.sin(a)
        p[axis_1] = c1 + r0 * math.sin(a) + r1 * math.cos(a)
        p[linear] = position[linear] + (block.xyz[linear] - position[linear]) * k / segments
        points.append(p)
    return points + [list(block.xyz)]
