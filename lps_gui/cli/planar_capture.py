"""`lps capture --planar`: planar (XY) plans on the simulated gantry, through the GRBL emulator, or on GRBL.

The planar half of :mod:`lps_gui.cli.capture` (SPEC 10), kept apart so the
1-D command stays as it is. Every switch is checked and the plan built
before a folder or a device is touched, so a typo costs nothing.

Examples::

    lps capture --planar --grid 0,0:40,20:10,10 --directions both --out xy1       # simulated gantry
    lps capture --planar --preset paper-planar --out xy2                             # the paper's 15 x 9 grid
    lps capture --planar --targets-xy "0,0;20,0;20,10;0,10" --stage emulator --out xy3
    lps capture --planar --iso-lines --grid 0,0:40,20:10,10 --out xy4                # ISO 230-2 lines per axis
    lps capture --planar --stage grbl:/dev/ttyUSB0 --camera 0 --board board.json --grid ... --out xy5
    lps capture --resume xy1
"""
from __future__ import annotations

import argparse
from dataclasses import replace
from typing import Any

PLANAR_PRESET_DEFAULT = "small-planar"
ISO_LEVELS = 3  # lines per axis of the --iso-lines preset: at both ends and the middle of the other axis
ISO_RUNS = 5  # ISO 230-2 asks for 5 runs per direction


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("planar XY plans (SPEC 10); --grid, --targets-xy or --iso-lines imply --planar")
    g.add_argument("--planar", action="store_true",
                   help="an XY gantry: a grid over both axes (simulated: presets small-planar, paper-planar)")
    g.add_argument("--grid", metavar="X0,Y0:X1,Y1:DX,DY", help="planar grid: start, stop and step in mm")
    g.add_argument("--pattern", choices=("serpentine", "raster"), help="planar grid order (default serpentine)")
    g.add_argument("--targets-xy", metavar="X,Y;X,Y;...", help="explicit planar targets in mm, in visiting order")
    g.add_argument("--iso-lines", action="store_true",
                   help=f"ISO 230-2 lines on the grid: along X at {ISO_LEVELS} Y levels and along Y at {ISO_LEVELS} "
                        f"X levels, forward and backward, {ISO_RUNS} runs")


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


def open_planar_capture(args: argparse.Namespace):
    """(session, stage, camera, engine) for a planar capture or resume; None when the command is 1-D."""
    if args.resume:
        from lps_gui.io.session import Session

        session = Session.open(args.resume)
        if not session.planar:
            if wants_planar(args):
                from lps_gui.errors import InputError

                raise InputError(f"{session.folder}: a single-axis session; resume it without the planar switches")
            return None
        return _resume(args, session)
    if not wants_planar(args):
        return None
    from lps_gui.errors import InputError

    if getattr(args, "compensation", None):
        raise InputError("--compensation: a table corrects one axis; planar plans are captured without one")
    if getattr(args, "iso_plan", False):
        raise InputError("--iso-plan is the single-axis ISO 230-2 preset; a planar plan takes --iso-lines")
    return _start(args)


def describe_planar(plan) -> str:
    """One line for the CLI: targets, extent, passes, frames."""
    t = plan.targets()
    dirs = {"+": "forward", "-": "backward", "both": "forward and backward"}[plan.directions]
    shape = "targets" if plan.targets_mm is not None else f"targets ({plan.pattern} grid)"
    return (f"{len(t)} {shape} X {t[:, 0].min():g}..{t[:, 0].max():g}, Y {t[:, 1].min():g}..{t[:, 1].max():g} mm, "
            f"{dirs}, {plan.runs} run(s), {plan.frames_per_stop} frame(s) per stop: {plan.n_frames()} frames")


# ----------------------------------------------------------------------------- the plan


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
    from lps_gui.core.plan import Plan
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
        from lps_gui.core.plan import iso_lines_on_grid

        plan = iso_lines_on_grid(plan, ISO_LEVELS, ISO_RUNS)
    if args.directions:
        plan = replace(plan, directions=args.directions)
    if args.runs is not None:
        plan = replace(plan, runs=args.runs)
    plan.n_frames()  # every field checked by the dataclass; the targets here
    return plan


def read_planar_plan(path: str):
    """A planar plan file (fields at the top level or under "plan", SPEC 10)."""
    from lps_gui.core.plan import Plan
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
    from lps_gui.core.simulate import PLANAR_PRESETS
    from lps_gui.errors import InputError

    name = PLANAR_PRESET_DEFAULT if preset in (None, "small") else preset
    if name not in PLANAR_PRESETS:
        raise InputError(f"--preset {preset}: the simulated gantry has presets {', '.join(PLANAR_PRESETS)}")
    return name


# ----------------------------------------------------------------------------- start and resume


def _start(args: argparse.Namespace):
    from lps_gui.cli.capture import _clock, _preflight, _read_intrinsics, bind_simulated_stage, device_session
    from lps_gui.errors import InputError

    stage_spec, camera_spec = args.stage or "sim", args.camera or "sim"
    _preflight(args, stage_spec, camera_spec)  # the stage against the camera, the image format
    if camera_spec == "sim":
        if args.board:
            raise InputError("--board: the simulated gantry's board comes from --preset; drop --board")
        if stage_spec not in ("sim", "emulator"):
            raise InputError(f"--stage {stage_spec}: the simulated camera rides only --stage sim or emulator")
        from lps_gui.core.simulate import PLANAR_PRESETS

        make_spec = PLANAR_PRESETS[planar_preset_name(args.preset)]
        plan = build_planar_plan(args, make_spec(seed=args.seed).plan)
        spec = make_spec(seed=args.seed, plan=plan)  # the camera centred over this plan
        from lps_gui.sim.rig import check_board_in_view

        check_board_in_view(spec)
        intr = _read_intrinsics(args.intrinsics)
        from lps_gui.sim.session import create_simulated_session, simulated_engine

        session, rig_stage, camera = create_simulated_session(args.out, spec, clock=_clock(args),
                                                                     noise_grey=args.noise_grey, intrinsics=intr)
        stage = bind_simulated_stage(args, session, rig_stage, camera, stage_spec, axes=["X", "Y"])
        return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
    if not args.board:
        raise InputError("--board FILE is required with a real camera (see SPEC 7 for board.json)")
    from lps_gui.io.board_file import read_board

    plan = build_planar_plan(args)
    board, intr = read_board(args.board), _read_intrinsics(args.intrinsics)
    return device_session(args, board, plan, intr, stage_spec, camera_spec, axes=["X", "Y"])


def _resume(args: argparse.Namespace, session):
    """A planar session on the simulated gantry goes on on the rebuilt gantry; None: on devices, as in 1-D."""
    from lps_gui.cli.capture import _bind_stage, _clock
    from lps_gui.errors import InputError

    given = [s for s, v in (("--grid", args.grid), ("--targets-xy", args.targets_xy), ("--iso-lines", args.iso_lines),
                            ("--pattern", args.pattern), ("--plan", args.plan)) if v]
    if given:
        raise InputError(f"{' '.join(given)}: a resumed session keeps its own plan; drop {given[0]}")
    truth = session.truth or {}
    if not (truth.get("simulated") and (args.camera or "sim") == "sim"):
        return None  # real devices: the engine takes the planar plan from the session as it is
    from lps_gui.sim.session import reopen_simulated_rig, simulated_engine

    rig_stage, camera = reopen_simulated_rig(session, clock=_clock(args))
    stage = _bind_stage(args.stage or "sim", rig_stage, args.time_scale)
    return session, stage, camera, simulated_engine(session, stage, camera, args.encode)
