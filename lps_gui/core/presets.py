"""Presets an operator picks instead of typing: stage specifications and the ISO 230-2 plan.

Stage specifications are data-sheet limits (um, read as +- for accuracy and
repeatability, as a full width for straight-line accuracy); "paper" is Table
1 of Vagharshakyan et al. (ACIIDS 2015): accuracy +-20 um, repeatability
+-5 um, straight-line accuracy 38 um. The ISO 230-2 plan takes 5 runs in
both directions over targets whose spacing is not uniform, so that every
target sits at a different phase of the lead-screw pitch (a uniform spacing
that is a multiple of the pitch would hide the periodic error, one that is
close to it would alias it). Pure data and numpy, no I/O.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from lps_gui.errors import InputError

SPEC_KEYS = {"accuracy": "accuracy_um", "repeatability": "repeatability_um", "straightness": "straightness_um"}
SPEC_PRESETS: dict[str, dict[str, float]] = {
    "paper": {"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0},  # the paper's Table 1
    "lead-screw-standard": {"accuracy_um": 50.0, "repeatability_um": 10.0, "straightness_um": 50.0},
    "ball-screw-precision": {"accuracy_um": 10.0, "repeatability_um": 2.0, "straightness_um": 10.0},
}
ISO_RUNS = 5
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def parse_spec(text: str) -> dict[str, float]:
    """``"paper"`` or ``"accuracy=20,repeatability=5,straightness=38"`` (um) -> session.json ``stage_spec``."""
    text = text.strip()
    if text in SPEC_PRESETS:
        return dict(SPEC_PRESETS[text])
    spec: dict[str, float] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = part.partition("=")
        key = key.strip().lower().removesuffix("_um")
        if not sep or key not in SPEC_KEYS:
            raise InputError(f"--spec {text!r}: give a preset ({', '.join(SPEC_PRESETS)}) or "
                             "accuracy=UM,repeatability=UM,straightness=UM")
        try:
            limit = float(value)
        except ValueError:
            raise InputError(f"--spec {key}={value!r}: the limit must be a number in um") from None
        if not limit > 0:
            raise InputError(f"--spec {key}={value}: a limit must be positive (um)")
        spec[SPEC_KEYS[key]] = limit
    if not spec:
        raise InputError(f"--spec {text!r}: empty; give a preset ({', '.join(SPEC_PRESETS)}) or accuracy=UM,...")
    return spec


def iso230_targets(start_mm: float, stop_mm: float, n_targets: int, pitch_mm: float | None = None) -> tuple[float, ...]:
    """Targets over [start, stop] that do not alias a lead-screw pitch (ISO 230-2 asks for non-uniform spacing).

    The ends are kept; each interior target is moved (by less than half the
    pitch, or a fifth of the spacing without a pitch) so its phase in the
    pitch follows the golden-ratio sequence, which covers the pitch evenly.
    """
    if n_targets < 2 or not stop_mm > start_mm:
        raise InputError("ISO 230-2 plan: need at least 2 targets and stop > start")
    spacing = (stop_mm - start_mm) / (n_targets - 1)
    nominal = start_mm + spacing * np.arange(n_targets)
    phase = (GOLDEN * np.arange(n_targets)) % 1.0
    if pitch_mm and 0 < pitch_mm <= spacing:
        base = np.floor((nominal - start_mm) / pitch_mm) * pitch_mm + start_mm
        moved = base + phase * pitch_mm
        moved = np.where(moved - nominal > pitch_mm / 2, moved - pitch_mm, moved)
    else:
        moved = nominal + (phase - 0.5) * 0.4 * spacing
    moved[0], moved[-1] = start_mm, stop_mm
    return tuple(float(round(v, 3)) for v in np.clip(moved, start_mm, stop_mm))


def iso230_plan_fields(start_mm: float, stop_mm: float, n_targets: int | None = None,
                       pitch_mm: float | None = None) -> dict[str, Any]:
    """Plan fields of the ISO 230-2 preset: 5 runs both ways over non-uniform targets (5 per metre, at least 5)."""
    n = n_targets or max(5, int(math.ceil((stop_mm - start_mm) / 1000.0 * 5)) + 1)
    return {"targets_mm": iso230_targets(start_mm, stop_mm, n, pitch_mm), "directions": "both", "runs": ISO_RUNS}
