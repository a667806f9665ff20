"""Compensation files for controllers, and the backlash and skew commands (docs/compensation-and-export.md).

- LinuxCNC ``COMP_FILE`` (``[JOINT_n]`` of the INI; ``docs/src/config/ini-config.adoc``):
  one ``nominal forward reverse`` triplet per line, ascending nominal, at most
  256 lines, machine units. ``COMP_FILE_TYPE = 0``: the actual positions moving
  up and down; ``COMP_FILE_TYPE = 1``: their offsets from nominal.
- Mach4 screw mapping (MachMotion's "Mach 4 Screw Mapping"): evenly spaced
  points from a start point over a length, one error per point and direction
  (asymmetric maps from build 4780); error = expected - actual position.
- CSV: ours, with the sigma of every entry; ``lps capture --compensation`` reads it back.
- grblHAL ``$160..$162`` and Marlin ``M425`` backlash; Klipper ``SET_SKEW``,
  Marlin ``M852``, RepRapFirmware ``M556`` skew.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from lps_gui.core.metrology.compensation import CompensationTable, skew_factor, skew_square_lengths
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic

FORMATS = ("linuxcnc", "linuxcnc-offsets", "mach4", "csv")
CSV_COLUMNS = ("nominal_mm", "actual_plus_mm", "actual_minus_mm", "offset_plus_um", "offset_minus_um",
               "sigma_plus_um", "sigma_minus_um")
AXES = "XYZ"


def linuxcnc_text(table: CompensationTable, offsets: bool = False) -> str:
    """COMP_FILE lines: type 0 (actual positions) or, with ``offsets``, type 1 (actual - nominal)."""
    x = np.asarray(table.nominal_mm)
    if offsets:
        a, b = np.asarray(table.actual_plus_mm) - x, np.asarray(table.actual_minus_mm) - x
    else:
        a, b = np.asarray(table.actual_plus_mm), np.asarray(table.actual_minus_mm)
    return "".join(f"{n:.6f} {p:.6f} {m:.6f}\n" for n, p, m in zip(x, a, b))


def mach4_text(table: CompensationTable) -> str:
    """Mach4 screw map: start, length and point count, then one error line per point (expected - actual, mm)."""
    x = np.asarray(table.nominal_mm)
    lines = [
        "# Mach4 screw mapping (Configure > Plugins > Machine Calibration > Linear Compensation)",
        f"# start_point {x[0]:.6f}",
        f"# length {x[-1] - x[0]:.6f}",
        f"# number_of_points {len(x)}",
        "# position error_positive error_negative   (error = expected - actual, machine units)",
    ]
    ep = x - np.asarray(table.actual_plus_mm)
    em = x - np.asarray(table.actual_minus_mm)
    lines += [f"{n:.6f} {p:.6f} {m:.6f}" for n, p, m in zip(x, ep, em)]
    return "\n".join(lines) + "\n"


def csv_text(table: CompensationTable) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    x = np.asarray(table.nominal_mm)
    cols = (x, table.actual_plus_mm, table.actual_minus_mm, table.offset_um(1), table.offset_um(-1),
            table.sigma_plus_um, table.sigma_minus_um)
    for row in zip(*cols):
        w.writerow([f"{v:.6f}" for v in row])
    return buf.getvalue()


def table_text(table: CompensationTable, fmt: str) -> str:
    if fmt == "linuxcnc":
        return linuxcnc_text(table)
    if fmt == "linuxcnc-offsets":
        return linuxcnc_text(table, offsets=True)
    if fmt == "mach4":
        return mach4_text(table)
    if fmt == "csv":
        return csv_text(table)
    raise InputError(f"--format {fmt}: choose one of {', '.join(FORMATS)}")


def write_table(path: Path | str, table: CompensationTable, fmt: str) -> Path:
    path = Path(path)
    write_bytes_atomic(path, table_text(table, fmt).encode())
    return path


# ----------------------------------------------------------------------------- reading back

def read_table(path: Path | str) -> CompensationTable:
    """Read our CSV or a LinuxCNC COMP_FILE (type 0 or 1, told apart by the size of the columns)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the compensation file ({exc.strerror or exc})") from exc
    lines = [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: empty compensation file; write one with `lps compensate`")
    try:
        if lines[0].startswith("nominal_mm"):
            rows = list(csv.DictReader(lines))
            col = {k: np.array([float(r[k]) for r in rows]) for k in CSV_COLUMNS}
            plus, minus = col["actual_plus_mm"], col["actual_minus_mm"]
            return CompensationTable(col["nominal_mm"], plus, minus, col["sigma_plus_um"], col["sigma_minus_um"],
                                     bidirectional=not np.array_equal(plus, minus))
        data = np.array([[float(v) for v in ln.split()] for ln in lines])
    except (ValueError, KeyError) as exc:
        raise InputError(f"{path}: not a compensation table ({exc}); use a file from `lps compensate`") from exc
    if data.ndim != 2 or data.shape[1] != 3:
        raise InputError(f"{path}: expected 3 numbers per line (nominal forward reverse)")
    x, a, b = data.T
    if float(np.median(np.abs(a - x))) > float(np.median(np.abs(a))):  # type 1: the columns are the small offsets
        a, b = x + a, x + b
    zeros = np.zeros_like(x)
    return CompensationTable(x, a, b, zeros, zeros, bidirectional=not np.array_equal(a, b))


# ----------------------------------------------------------------------------- backlash and skew

def backlash_lines(backlash_um: float, axis: str = "X") -> list[str]:
    """grblHAL ``$16n`` (mm, axis n = X0 Y1 Z2) and Marlin ``M425`` (mm, full correction F1)."""
    if axis not in AXES:
        raise InputError(f"axis {axis!r}: choose X, Y or Z")
    mm = max(float(backlash_um), 0.0) * 1e-3
    return [
        f"${160 + AXES.index(axis)}={mm:.4f}    ; grblHAL backlash compensation, {axis} (mm; needs ENABLE_BACKLASH_COMPENSATION)",
        f"M425 F1 {axis}{mm:.4f}    ; Marlin backlash compensation (mm), then M500 to save",
    ]


def skew_lines(squareness_urad: float, side_mm: float = 100.0) -> list[str]:
    """Klipper ``SET_SKEW XY=AC,BD,AD``, Marlin ``M852 I<factor>`` and RepRapFirmware ``M556 S<len> X<dev>``."""
    ac, bd, ad = skew_square_lengths(squareness_urad, side_mm)
    factor = skew_factor(squareness_urad)
    return [
        f"SET_SKEW XY={ac:.4f},{bd:.4f},{ad:.4f}    ; Klipper [skew_correction]",
        f"M852 I{factor:.6f}    ; Marlin SKEW_CORRECTION_GCODE",
        f"M556 S{side_mm:g} X{factor * side_mm:.4f}    ; RepRapFirmware axis compensation",
    ]
