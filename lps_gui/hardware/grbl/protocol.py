"""GRBL 1.1 messages as data: classify a line, parse status reports, $I and $$, format commands.

Pure functions shared by the driver (which parses what GRBL says) and the
emulator (which formats what GRBL would say), so both sides follow one
reading of GRBL's ``doc/markdown/interface.md``:

- responses ``ok`` / ``error:N`` answer exactly one sent line;
- push messages (``<...>`` status, banner, ``ALARM:N``, ``[MSG:...]``, other
  ``[TAG:...]`` feedback, ``$N=value`` settings, ``>line:ok`` startup lines)
  arrive on their own and are not counted;
- a status report is ``<State[:sub]|MPos:x,y,z or WPos:x,y,z|field:values...>``;
  WCO, Ov and Bf are optional and appear per $10 and GRBL's refresh counters.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import NamedTuple

STATES = ("Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep")
BANNER_RE = re.compile(r"^Grbl (\d+\.\d+[a-z]?) \['\$' for help\]$")
MM_PER_INCH = 25.4

Axes = tuple[float, float, float]


class Message(NamedTuple):
    """One line from GRBL: ``kind`` is ok, error, alarm, status, banner, msg, feedback, setting, startup or unknown."""

    kind: str
    code: int | None = None
    text: str = ""
    status: "StatusReport | None" = None


@dataclass(frozen=True)
class StatusReport:
    """A parsed ``<...>`` report; absent fields are None (positions in the report's units)."""

    state: str
    substate: int | None = None
    mpos: Axes | None = None
    wpos: Axes | None = None
    wco: Axes | None = None
    buffer: tuple[int, int] | None = None  # planner blocks free, RX bytes free
    line_number: int | None = None
    feed: float | None = None
    spindle: float | None = None
    pins: str = ""
    overrides: tuple[int, int, int] | None = None  # feed, rapid, spindle %
    accessories: str = ""


class BuildInfo(NamedTuple):
    """``$I``: ``[VER:1.1h.20190830:user]`` and ``[OPT:V,15,128]``."""

    version: str
    build: str
    user: str
    options: str
    planner_blocks: int
    rx_buffer_bytes: int


def _axes(text: str) -> Axes:
    vals = tuple(float(v) for v in text.split(","))
    if len(vals) < 1:
        raise ValueError(text)
    return (vals + (0.0, 0.0, 0.0))[:3]  # type: ignore[return-value]


def parse_status(line: str) -> StatusReport:
    """Parse ``<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:...>``; ValueError if it is not one."""
    if not (line.startswith("<") and line.endswith(">")):
        raise ValueError(f"not a status report: {line!r}")
    fields = line[1:-1].split("|")
    state, _, sub = fields[0].partition(":")
    if state not in STATES:
        raise ValueError(f"unknown state {state!r} in {line!r}")
    kw: dict = {"state": state, "substate": int(sub) if sub else None}
    for f in fields[1:]:
        key, sep, val = f.partition(":")
        if not sep:
            raise ValueError(f"bad field {f!r} in {line!r}")
        if key == "MPos":
            kw["mpos"] = _axes(val)
        elif key == "WPos":
            kw["wpos"] = _axes(val)
        elif key == "WCO":
            kw["wco"] = _axes(val)
        elif key == "Bf":
            a, b = val.split(",")
            kw["buffer"] = (int(a), int(b))
        elif key == "Ln":
            kw["line_number"] = int(val)
        elif key == "FS":
            a, b = val.split(",")
            kw["feed"], kw["spindle"] = float(a), float(b)
        elif key == "F":
            kw["feed"] = float(val)
        elif key == "Pn":
            kw["pins"] = val
        elif key == "Ov":
            a, b, c = val.split(",")
            kw["overrides"] = (int(a), int(b), int(c))
        elif key == "A":
            kw["accessories"] = val
        # unknown fields (forks, future versions) are ignored on purpose
    if "mpos" not in kw and "wpos" not in kw:
        raise ValueError(f"status report without MPos or WPos: {line!r}")
    return StatusReport(**kw)


def classify(line: str) -> Message:
    """What kind of GRBL message ``line`` (without CR/LF) is."""
    if line == "ok":
        return Message("ok")
    if line.startswith("error:") and line[6:].isdigit():
        return Message("error", int(line[6:]))
    if line.startswith("ALARM:") and line[6:].isdigit():
        return Message("alarm", int(line[6:]))
    if line.startswith("<"):
        try:
            return Message("status", text=line, status=parse_status(line))
        except ValueError:
            return Message("unknown", text=line)
    m = BANNER_RE.match(line)
    if m:
        return Message("banner", text=m.group(1))
    if line.startswith("[MSG:") and line.endswith("]"):
        return Message("msg", text=line[5:-1])
    if line.startswith("[") and line.endswith("]") and ":" in line:
        return Message("feedback", text=line[1:-1])
    m = re.match(r"^\$(\d+)=(-?[\d.]+)$", line)
    if m:
        return Message("setting", int(m.group(1)), m.group(2))
    if line.startswith(">") and (line.endswith(":ok") or re.search(r":error:\d+$", line)):
        return Message("startup", text=line[1:])
    return Message("unknown", text=line)


def parse_build_info(lines: list[str]) -> BuildInfo:
    """From the ``[VER:...]`` and ``[OPT:...]`` lines of ``$I``."""
    ver = next((ln for ln in lines if ln.startswith("[VER:")), None)
    opt = next((ln for ln in lines if ln.startswith("[OPT:")), None)
    if ver is None:
        raise ValueError("no [VER:] line in the $I reply")
    body = ver[5:-1]
    vb, _, user = body.partition(":")
    version, build = vb.rsplit(".", 1) if vb.count(".") >= 2 else (vb, "")
    blocks, rx, options = 15, 128, ""
    if opt is not None:
        parts = opt[5:-1].split(",")
        options = parts[0]
        if len(parts) >= 3:
            blocks, rx = int(parts[1]), int(parts[2])
    return BuildInfo(version, build, user, options, blocks, rx)


def parse_settings(lines: list[str]) -> dict[int, float]:
    """``{N: value}`` from the ``$N=value`` lines of ``$$``."""
    out: dict[int, float] = {}
    for ln in lines:
        m = classify(ln)
        if m.kind == "setting":
            out[int(m.code)] = float(m.text)
    return out


def format_axes(values: Axes, inches: bool = False) -> str:
    """``x,y,z`` with 3 decimals in mm (4 in inches), as GRBL prints coordinates."""
    if inches:
        return ",".join(f"{v / MM_PER_INCH:.4f}" for v in values)
    return ",".join(f"{v:.3f}" for v in values)


def format_status(r: StatusReport, inches: bool = False) -> str:
    """The ``<...>`` line GRBL would send for ``r`` (field order as in report.c)."""
    state = r.state if r.substate is None else f"{r.state}:{r.substate}"
    parts = [state]
    if r.mpos is not None:
        parts.append("MPos:" + format_axes(r.mpos, inches))
    else:
        parts.append("WPos:" + format_axes(r.wpos or (0.0, 0.0, 0.0), inches))
    if r.buffer is not None:
        parts.append(f"Bf:{r.buffer[0]},{r.buffer[1]}")
    if r.line_number:
        parts.append(f"Ln:{r.line_number}")
    feed = (r.feed or 0.0) / (MM_PER_INCH if inches else 1.0)
    parts.append(f"FS:{feed:.{1 if inches else 0}f},{r.spindle or 0.0:.0f}")
    if r.pins:
        parts.append(f"Pn:{r.pins}")
    if r.wco is not None:
        parts.append("WCO:" + format_axes(r.wco, inches))
    if r.overrides is not None:
        parts.append("Ov:" + ",".join(str(v) for v in r.overrides))
        if r.accessories:
            parts.append(f"A:{r.accessories}")
    return "<" + "|".join(parts) + ">"


def _num(v: float) -> str:
    return f"{v:.4f}".rstrip("0").rstrip(".") if v != int(v) else f"{int(v)}"


DWELL_RE = re.compile(r"G0*4(?![0-9.]).*?P([0-9]*\.?[0-9]+)")


def dwell_seconds(line: str) -> float:
    """P of a ``G4`` dwell in ``line`` (seconds), 0 for any other line."""
    m = DWELL_RE.search(re.sub(r"\([^)]*\)|;.*|\s", "", line.upper()))
    return float(m.group(1)) if m else 0.0


def move_line(position_mm: float, feed_mm_min: float, axis: str = "X") -> str:
    """An absolute metric feed move, e.g. ``G90 G21 G1 X12.5 F600``."""
    return f"G90 G21 G1 {axis}{_num(position_mm)} F{_num(feed_mm_min)}"


def jog_line(distance_mm: float, feed_mm_min: float, axis: str = "X") -> str:
    """An incremental metric jog, e.g. ``$J=G91 G21 X0.5 F1000`` (every jog needs its F)."""
    return f"$J=G91 G21 {axis}{_num(distance_mm)} F{_num(feed_mm_min)}"


def parse_offsets(lines: list[str]) -> dict[str, Axes]:
    """The ``$#`` reply's coordinate offsets by name (``[G54:-500.000,0.000,0.000]`` -> {"G54": (-500, 0, 0)})."""
    out: dict[str, Axes] = {}
    for line in lines:
        m = re.match(r"^\[(G5[4-9]|G28|G30|G92):([-\d.,]+)\]$", line.strip())
        if m:
            out[m.group(1)] = _axes(m.group(2))
    return out


def parse_work_system(lines: list[str]) -> str | None:
    """The active work coordinate system in a ``$G`` reply (``[GC:G0 G55 G17 ...]``), None if absent."""
    for line in lines:
        if line.startswith("[GC:"):
            m = re.search(r"\bG5[4-9]\b", line)
            if m:
                return m.group(0)
    return None
