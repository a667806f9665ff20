"""The plan of `lps capture` from its switches: one axis (SPEC 7) or an XY grid (SPEC 10).

Every switch is checked and the plan built before a folder or a device is
touched, so a typo costs nothing.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

PLANAR_PRESET_DEFAULT = "small-planar"
ISO_LEVELS = 3  # lines per axis of the --iso-lines preset: at both ends and the middle of the other axis
ISO_RUNS = 5  # ISO 230-2 asks for 5 runs per direction


def wants_planar(args: argparse.Namespace) -> bool:
    """A planar switch, or a --plan file whose axes are [X, Y] (a planar session.json is a plan file too)."""
    if getattr(args, "planar", False) or args.grid or args.targets_xy or args.iso_lines:
        return True
    return bool(args.plan) and _plan_file_axes(args.plan) == ["X", "Y"]


def _plan_fields(path: str) -> dict | None:
    """The plan fields of a plan file (top level or under "plan"); None when it is not a JSON object."""
    from lps_gui.io.jsonfile import read_json

    d = read_json(path, "plan file")
    if isinstance(d, dict) and isinstance(d.get("plan"), dict):
        d = d["plan"]
    return d if isinstance(d, dict) else None


def _plan_file_axes(path: str) -> list[str] | None:
    return (_plan_fields(path) or {}).get("axes")


def describe(plan) -> str:
    """One line for the CLI: targets, extent, passes, frames (and stage time on one axis)."""
    if not plan.planar:
        from lps_gui.capture.plans import describe_plan, plan_duration_s

        return f"{describe_plan(plan)}, about {plan_duration_s(plan) / 60:.1f} min of stage time"
    t = plan.targets()
    dirs = {"+": "forward", "-": "backward", "both": "forward and backward"}[plan.directions]
    shape = "targets" if plan.targets_mm is not None else f"targets ({plan.pattern} grid)"
    return (f"{len(t)} {shape} X {t[:, 0].min():g}..{t[:, 0].max():g}, Y {t[:, 1].min():g}..{t[:, 1].max():g} mm, "
            f"{dirs}, {plan.runs} run(s), {plan.frames_per_stop} frame(s) per stop: {plan.n_frames()} frames")


def parse_grid(text: str) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
    """``"0,0:40,20:10,10"`` -> ((0, 0), (40, 20), (10, 10)) in mm."""
    from lps_gui.errors import InputError

    try:
        parts = [tuple(float(v) for v in part.split(",")) for part in text.split(":")]
    except ValueError:
        parts = []
    if len(parts) != 3 or any(len(p) != 2 for p in parts):
        raise InputError(f"--grid {text!r}: give X0,Y0:X1,Y1:DX,DY in mm, e.g. 0,0:40,20:10,10")
    return parts[0], parts[1], parts[2]  # type: ignore[return-value]


def parse_targets_xy(text: str) -> tuple[tuple[float, float], ...]:
    """``"0,0;10,0;10,5"`` -> ((0, 0), (10, 0), (10, 5)) in mm."""
    from lps_gui.errors import InputError

    out = []
    for item in (t for t in text.split(";") if t.strip()):
        try:
            x, y = (float(v) for v in item.split(","))
        except ValueError:
            raise InputError(f"--targets-xy: {item.strip()!r} is not X,Y; give X,Y;X,Y;... in mm") from None
        out.append((x, y))
    return tuple(out)


def build_planar_plan(args: argparse.Namespace, base=None):
    """The planar plan of the command line: --plan FILE, --grid / --targets-xy / --iso-lines, then the switches."""
    from lps_gui.core.planning.plan import Plan
    from lps_gui.errors import InputError

    for name in ("start_mm", "stop_mm", "step_mm"):
        if getattr(args, name) is not None:
            raise InputError(f"--{name[:-3]}: a planar plan takes --grid X0,Y0:X1,Y1:DX,DY (or --targets-xy)")
    if args.targets:
        raise InputError("--targets: a planar plan takes --targets-xy \"X,Y;X,Y;...\"")
    if args.grid and args.targets_xy:
        raise InputError("give either --grid or --targets-xy, not both")
    if args.iso_lines and args.targets_xy:
        raise InputError("--iso-lines builds its lines on a --grid (or the preset's grid); drop --targets-xy")
    if args.plan:
        base = read_planar_plan(args.plan)
    plan = base or Plan.xy()
    if args.grid:
        start, stop, step = parse_grid(args.grid)
        plan = Plan.xy(start_mm=start, stop_mm=stop, step_mm=step, pattern=plan.pattern,
                       **{k: getattr(plan, k) for k in ("directions", "runs", "overshoot_mm", "settle_s",
                                                          "frames_per_stop", "feed_mm_min")})
    elif args.targets_xy:
        plan = replace(plan, targets_mm=parse_targets_xy(args.targets_xy))
    fields = {k: getattr(args, k) for k in ("overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min")}
    plan = replace(plan, **{k: v for k, v in fields.items() if v is not None})
    if args.pattern:
        if plan.targets_mm is not None and not args.iso_lines:
            raise InputError("--pattern orders a --grid; explicit --targets-xy are visited as listed")
        plan = replace(plan, pattern=args.pattern)
    if args.iso_lines:
        if plan.targets_mm is not None:
            raise InputError("--iso-lines needs a grid: give --grid X0,Y0:X1,Y1:DX,DY")
        from lps_gui.core.planning.plan import iso_lines_on_grid

        plan = iso_lines_on_grid(plan, ISO_LEVELS, ISO_RUNS)
    if args.directions:
        plan = replace(plan, directions=args.directions)
    if args.runs is not None:
        plan = replace(plan, runs=args.runs)
    plan.n_frames()  # every field checked by the dataclass; the targets here
    return plan


def read_planar_plan(path: str):
    """A planar plan file (fields at the top level or under "plan", SPEC 10)."""
    from lps_gui.core.planning.plan import Plan
    from lps_gui.errors import InputError

    d = _plan_fields(path)
    if d is None:
        raise InputError(f"{path}: a planar plan file is a JSON object with start_mm: [x, y], stop_mm, step_mm...")
    try:
        return Plan.from_dict(d)
    except (InputError, TypeError) as exc:
        raise InputError(f"{path}: {exc}") from exc


def planar_preset_name(preset: str | None) -> str:
    """The simulated gantry's preset (the 1-D default "small" means small-planar)."""
    from lps_gui.core.truth.simulate import PLANAR_PRESETS
    from lps_gui.errors import InputError

    name = PLANAR_PRESET_DEFAULT if preset in (None, "small") else preset
    if name not in PLANAR_PRESETS:
        raise InputError(f"--preset {preset}: the simulated gantry has presets {', '.join(PLANAR_PRESETS)}")
    return name


def line_plan(args: argparse.Namespace, base=None):
    """The single-axis plan of the command line: --plan FILE, then the switches (SPEC 7)."""
    from lps_gui.capture.plans import parse_targets, plan_with, read_plan

    if args.plan:
        base = read_plan(args.plan)
    fields = {k: getattr(args, k) for k in ("start_mm", "stop_mm", "step_mm", "directions", "runs", "overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min")}
    if args.targets:
        fields["targets_mm"] = parse_targets(args.targets)
    from lps_gui.cli.capture.setup import iso_plan_fields

    fields.update(iso_plan_fields(args, base))
    from lps_gui.cli.capture.asme_test import test_plan_fields

    start = args.start_mm if args.start_mm is not None else getattr(base, "start_mm", None)
    fields.update(test_plan_fields(args, start, args.stop_mm if args.stop_mm is not None else getattr(base, "stop_mm", None)))
    if base is None and not any(fields[k] is not None for k in ("start_mm", "stop_mm", "step_mm", "targets_mm") if k in fields):
        from lps_gui.errors import InputError

        raise InputError("no plan: give --plan FILE or --start/--stop/--step (or --targets)")
    plan = plan_with(base, **fields)
    if getattr(args, "segment_stops", None):  # one board moved between overlapping segments (SPEC 13 stitching)
        from lps_gui.core.planning.segments import stitched_segments

        plan = plan_with(plan, segments=stitched_segments(plan.targets(), args.segment_stops, args.overlap_stops))
    return plan
