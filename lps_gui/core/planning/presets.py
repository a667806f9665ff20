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

SPEC_KEYS = {"accuracy": "accuracy_um", "repeatability": "repeatability_um", "straightness": "straightness_um",
             "min_step": "min_incremental_motion_um", "settling": "settling_time_s"}  # the last two: ASME B5.64 tests
SPEC_PRESETS: dict[str, dict[str, float]] = {
    "paper": {"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0},  # the paper's Table 1
    "lead-screw-standard": {"accuracy_um": 50.0, "repeatability_um": 10.0, "straightness_um": 50.0},
    "ball-screw-precision": {"accuracy_um": 10.0, "repeatability_um": 2.0, "straightness_um": 10.0},
}
ISO_RUNS = 5
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def parse_spec(text: str) -> dict[str, float]:
    """``"paper"``, ``"accuracy=20,repeatability=5,straightness=38"`` (um) or both (``"paper,min_step=2"``) -> session.json ``stage_spec``."""
    text = text.strip()
    if text in SPEC_PRESETS:
        return dict(SPEC_PRESETS[text])
    spec: dict[str, float] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        if part in SPEC_PRESETS:  # a preset with more limits: "paper,min_step=2"
            spec.update(SPEC_PRESETS[part])
            continue
        key, sep, value = part.partition("=")
        key = key.strip().lower().removesuffix("_um").removesuffix("_s").replace("-", "_")
        if not sep or key not in SPEC_KEYS:
            raise InputError(f"--spec {text!r}: give a preset ({', '.join(SPEC_PRESETS)}) or "
                             "accuracy=UM,repeatability=UM,straightness=UM (ASME B5.64 tests: min_step=UM, settling=S)")
        try:
            limit = float(value)
        except ValueError:
            raise InputError(f"--spec {key}={value!r}: the limit must be a number ({'s' if key == 'settling' else 'um'})") from None
        if not limit > 0:
            raise InputError(f"--spec {key}={value}: a limit must be positive ({'s' if key == 'settling' else 'um'})")
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


# ----------------------------------------------------------------------------- ASME B5.64 test plans

ASME_TESTS = ("min-step", "settling")  # the plan presets of the ASME B5.64 tests (session.json ``asme_test``)
MIN_STEP_UM = 2.0
MIN_STEP_COUNT = 10  # steps per location
MIN_STEP_LOCATIONS = 3  # places along the travel: the spread fixes the line the tiny steps could not
MIN_STEP_FRAMES = 8
SETTLING_STOPS = 3
SETTLING_FRAMES = 100
SETTLING_BAND_UM = 5.0
PAPER_SPEC_TEST_LIMITS = {"min_incremental_motion_um": 2.0, "settling_time_s": 1.0}  # the demo's data sheet for the tests


def min_step_plan_fields(start_mm: float, stop_mm: float, step_um: float = MIN_STEP_UM, steps: int = MIN_STEP_COUNT,
                         locations: int = MIN_STEP_LOCATIONS, frames: int = MIN_STEP_FRAMES) -> dict[str, Any]:
    """Plan fields of the incremental-step (minimum incremental motion) test.

    ``steps`` steps of ``step_um`` forward, then back (directions "both"), at
    ``locations`` places spread over [start, stop]: the steps measure the
    stage's smallest motion, the spread between the places fixes the motion
    direction that micrometres of travel alone could not. ``frames`` frames
    per stop are averaged (noise / sqrt(frames)).
    """
    if not stop_mm > start_mm or locations < 2 or steps < 1 or not step_um > 0 or frames < 1:
        raise InputError("min-step plan: need stop > start, 2 or more locations, a positive step (um) and frames >= 1")
    span_mm = 1e-3 * step_um * steps
    if span_mm * locations >= stop_mm - start_mm:
        raise InputError(f"min-step plan: {steps} steps of {step_um:g} um at {locations} places do not fit "
                         f"{start_mm:g}..{stop_mm:g} mm; widen the travel or take fewer steps")
    bases = np.linspace(start_mm, stop_mm - span_mm, locations)
    targets = (bases[:, None] + 1e-3 * step_um * np.arange(steps + 1)[None, :]).ravel()
    return {"targets_mm": tuple(float(round(v, 6)) for v in targets), "directions": "both", "runs": 1,
            "frames_per_stop": int(frames)}


def settling_plan_fields(start_mm: float, stop_mm: float, stops: int = SETTLING_STOPS,
                         frames: int = SETTLING_FRAMES) -> dict[str, Any]:
    """Plan fields of the settling test: moves between ``stops`` targets both ways, then ``frames`` frames
    grabbed back to back from the end of each move (no settle wait): position against time."""
    if not stop_mm > start_mm or stops < 2 or frames < 8:
        raise InputError("settling plan: need stop > start, 2 or more stops and 8 or more frames per stop")
    targets = np.linspace(start_mm, stop_mm, stops)
    return {"targets_mm": tuple(float(round(v, 6)) for v in targets), "directions": "both", "runs": 1,
            "frames_per_stop": int(frames), "settle_s": 0.0}


def asme_test_record(test: str, **params: Any) -> dict[str, Any]:
    """session.json ``asme_test``: which ASME B5.64 test the plan is, and its parameters."""
    if test not in ASME_TESTS:
        raise InputError(f"--test {test}: choose one of {', '.join(ASME_TESTS)}")
    defaults = {"min-step": {"step_um": MIN_STEP_UM}, "settling": {"band_um": SETTLING_BAND_UM}}[test]
    return {"test": test, **defaults, **{k: float(v) for k, v in params.items() if v is not None}}
