"""Is a results.json one an estimate could have written? Checked on every read.

A results.json edited by hand, truncated to ``"positions": []`` or holding
NaN or 1e308 where a measured position belongs would otherwise give a report,
a compensation table or an export of dashes or of absurd numbers with exit 0.
Only what every reader relies on is checked: the sections' types and, in the
rows of views the estimate used, the measured positions and deviations.
"""
from __future__ import annotations

import math
from typing import Any

from lps_gui.errors import InputError

MAX_ABS_VALUE = 1e9  # mm or um: no stage measured by a camera is a kilometre long or off by one
LINE_KEYS = ("target_mm", "measured_mm", "deviation_um")
PLANAR_KEYS = ("target_x_mm", "target_y_mm", "measured_x_mm", "measured_y_mm", "deviation_x_um", "deviation_y_um")


def check_results(data: dict[str, Any], source: str) -> None:
    """InputError naming ``source`` and the first field that no estimate writes."""
    fix = "re-run `lps estimate` on the session"
    for name, kind in (("parameters", dict), ("positions", list), ("figures", dict)):
        if name in data and not isinstance(data[name], kind):
            raise InputError(f"{source}: '{name}' is not a JSON {'object' if kind is dict else 'list'}; {fix}")
    rows = data.get("positions")
    if not rows:
        raise InputError(f"{source}: has no per-position table (no positions); {fix}")
    planar = len(data.get("axes") or ["X"]) == 2
    keys = PLANAR_KEYS if planar else LINE_KEYS
    measured = 0
    for i, row in enumerate(rows):
        if not isinstance(row, dict):
            raise InputError(f"{source}: position {i} is not a JSON object; {fix}")
        if not row.get("used", not row.get("outlier")):
            continue
        for key in keys:
            value = row.get(key)
            if value is None:  # not estimated (a method without that figure)
                continue
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) \
                    or abs(value) > MAX_ABS_VALUE:
                raise InputError(f"{source}: position {i} ({key}) is {value!r}, not a measured value; {fix}")
            measured += key.startswith("measured")
    if not measured:
        raise InputError(f"{source}: no position holds a measured value; {fix}")
