"""Plan files and plan options: the ``--plan plan.json`` file and the ``--start/--stop/...`` switches.

A plan file holds the fields of :class:`~lps_gui.core.planning.plan.Plan` at the top
level or under ``"plan"`` (so a session.json is a valid plan file too):
``{"start_mm": 0, "stop_mm": 38, "step_mm": 2, "directions": "both", "runs": 2,
"overshoot_mm": 1, "settle_s": 0.2, "frames_per_stop": 1, "feed_mm_min": 600}``
or ``"targets_mm": [...]`` instead of start/stop/step.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError
from lps_gui.io.jsonfile import read_json


def read_plan(path: Path | str) -> Plan:
    """Read a plan file (fields at the top level or under "plan")."""
    d = read_json(path, "plan file")
    if isinstance(d, dict) and isinstance(d.get("plan"), dict):
        d = d["plan"]
    if not isinstance(d, dict):
        raise InputError(f"{path}: a plan file is a JSON object with start_mm, stop_mm, step_mm...")
    try:
        return Plan.from_dict(d)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from exc


def plan_with(base: Plan | None, **fields: Any) -> Plan:
    """``base`` (or the default Plan) with every field given as not None replaced.

    Giving ``start_mm``/``stop_mm``/``step_mm`` drops explicit targets of
    the base; giving ``targets_mm`` replaces them.
    """
    given = {k: v for k, v in fields.items() if v is not None}
    unknown = set(given) - set(Plan.__dataclass_fields__)
    if unknown:
        raise InputError(f"plan: unknown fields {sorted(unknown)}")
    if "targets_mm" in given:
        given["targets_mm"] = tuple(float(t) for t in given["targets_mm"])
    elif {"start_mm", "stop_mm", "step_mm"} & set(given):
        given["targets_mm"] = None
    return replace(base or Plan(), **given)


def parse_targets(text: str) -> tuple[float, ...]:
    """``"0,1.5,3"`` -> (0.0, 1.5, 3.0) for ``--targets``."""
    parts = text.replace(";", ",").strip().strip(",").split(",")
    try:
        if not all(p.strip() for p in parts):  # "1,2,,3": a position lost in typing, not one to drop quietly
            raise ValueError
        return tuple(float(t) for t in parts)
    except ValueError:
        raise InputError(f"--targets {text!r}: give comma-separated positions in mm, e.g. 0,1.5,3 (no empty entry)") from None


def describe_plan(plan: Plan) -> str:
    """One line for logs and the CLI: targets, directions, runs, frames."""
    t = plan.targets()
    dirs = {"+": "forward", "-": "backward", "both": "forward and backward"}[plan.directions]
    return (
        f"{len(t)} targets {t[0]:g}..{t[-1]:g} mm, {dirs}, {plan.runs} run(s), "
        f"{plan.frames_per_stop} frame(s) per stop: {plan.n_frames()} frames"
    )


def plan_duration_s(plan: Plan, accel_mm_s2: float = 200.0, grab_s: float = 0.05, start_mm: float = 0.0) -> float:
    """Rough time a plan takes on a stage (s): moves at the plan's feed with ``accel_mm_s2``, settles, grabs.

    For the estimate shown before a capture starts; the engine's running
    ETA replaces it once frames come in.
    """
    from lps_gui.hardware.motion import duration_s

    positions = [start_mm]
    for direction in plan.run_directions():
        ordered = plan.targets() if direction == "+" else plan.targets()[::-1]
        positions += [plan.approach_start_mm(direction, float(ordered[0])), *map(float, ordered)]
    moves = np.abs(np.diff(positions))
    one_pass = sum(duration_s(d, plan.feed_mm_min, accel_mm_s2) for d in moves)
    n_stops = len(plan.targets()) * len(plan.run_directions())
    return plan.runs * (one_pass + n_stops * (plan.settle_s + plan.frames_per_stop * grab_s))
