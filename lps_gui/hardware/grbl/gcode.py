"""The G-code subset the GRBL emulator understands, checked with GRBL's own error codes.

Lines arrive pre-filtered as GRBL's protocol loop leaves them (no spaces, no
comments, upper case, see :func:`clean_line`). :func:`parse_block` splits a
block into words and validates it per GRBL 1.1's gcode.c rules that matter
for a positioning stage: letters and numbers (error 1, 2), repeated words
(25), modal-group conflicts (21), unsupported commands (20), unused words
(36), jog restrictions (16, 22, 26), dwell without P (28).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

NUMBER_RE = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)")
LINE_BUFFER_SIZE = 80  # GRBL's LINE_BUFFER_SIZE: longer lines answer error:11

# modal groups of the G words we accept (GRBL numbering of the groups is irrelevant here)
G_GROUPS = {
    0.0: "motion", 1.0: "motion", 4.0: "non_modal", 10.0: "non_modal", 53.0: "non_modal",
    90.0: "distance", 91.0: "distance", 20.0: "units", 21.0: "units",
    17.0: "plane", 18.0: "plane", 19.0: "plane", 94.0: "feed_mode", 54.0: "coord",
}
M_GROUPS = {0: "stop", 1: "stop", 2: "stop", 30: "stop", 3: "spindle", 4: "spindle", 5: "spindle",
            7: "coolant", 8: "coolant", 9: "coolant"}
AXIS_LETTERS = "XYZ"
VALUE_LETTERS = "NFPSTXYZL"
KNOWN_UNUSED = "IJKRQ"  # GRBL knows them, but nothing here uses them: error:36
JOG_G = {20.0, 21.0, 90.0, 91.0, 53.0}


class CodeError(Exception):
    """A GRBL ``error:N`` found while parsing a line."""

    def __init__(self, code: int) -> None:
        super().__init__(code)
        self.code = code


@dataclass
class Block:
    """One parsed block: G and M commands by modal group, and value words."""

    g: dict[str, float] = field(default_factory=dict)
    m: dict[str, int] = field(default_factory=dict)
    words: dict[str, float] = field(default_factory=dict)

    @property
    def axes(self) -> dict[str, float]:
        return {k: v for k, v in self.words.items() if k in AXIS_LETTERS}


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


def _words(text: str) -> list[tuple[str, float]]:
    out, i = [], 0
    while i < len(text):
        letter = text[i]
        if not ("A" <= letter <= "Z"):
            raise CodeError(1)
        m = NUMBER_RE.match(text, i + 1)
        if not m:
            raise CodeError(2)
        out.append((letter, float(m.group())))
        i = m.end()
    return out


def parse_block(text: str, jog: bool = False) -> Block:
    """Parse a cleaned block (for a jog, the part after ``$J=``); raise CodeError(N) like GRBL."""
    block = Block()
    for letter, value in _words(text):
        if letter == "G":
            group = G_GROUPS.get(round(value, 1))
            if group is None:
                raise CodeError(16 if jog else 20)
            if group in block.g:
                raise CodeError(21)
            if jog and round(value, 1) not in JOG_G:
                raise CodeError(16)
            block.g[group] = round(value, 1)
        elif letter == "M":
            if jog:
                raise CodeError(16)
            group = M_GROUPS.get(int(value)) if value == int(value) else None
            if group is None:
                raise CodeError(20)
            if group in block.m:
                raise CodeError(21)
            block.m[group] = int(value)
        elif letter in VALUE_LETTERS or letter in KNOWN_UNUSED:
            if letter in block.words:
                raise CodeError(25)
            block.words[letter] = value
        else:
            raise CodeError(20)
    if "N" in block.words and not (0 <= block.words["N"] <= 9999999):
        raise CodeError(27)
    if "F" in block.words and block.words["F"] < 0:
        raise CodeError(4)
    if jog:
        if "F" not in block.words:
            raise CodeError(22)
        if not block.axes:
            raise CodeError(26)
        if set(block.words) - set("NFXYZ"):
            raise CodeError(36)
        return block
    if set(block.words) & set(KNOWN_UNUSED):
        raise CodeError(36)
    if block.g.get("non_modal") == 10.0:  # gcode.c: L2/L20 with P0..P6; only G54 (P0/P1) is emulated
        if "L" not in block.words or "P" not in block.words:
            raise CodeError(28)
        if block.words["L"] not in (2, 20) or block.words["P"] != int(block.words["P"]) or not 0 <= block.words["P"] <= 6:
            raise CodeError(20)
        if block.words["P"] > 1:
            raise CodeError(20)  # G55-G59 not emulated
        if not block.axes:
            raise CodeError(26)
        return block
    if "L" in block.words:
        raise CodeError(36)
    if block.g.get("non_modal") == 4.0:
        if "P" not in block.words:
            raise CodeError(28)
        if block.words["P"] < 0:
            raise CodeError(4)
        if block.axes:
            raise CodeError(31)
    elif "P" in block.words:
        raise CodeError(36)
    if block.g.get("non_modal") == 53.0 and block.g.get("motion", 0.0) not in (0.0, 1.0):
        raise CodeError(30)
    return block
