"""`lps simulate`: sessions with known truth (points, rendered images, intrinsics sets)."""
from __future__ import annotations

import argparse

from lps_gui.cli.option_types import float_range, int_range, nonnegative_finite, nonnegative_int

HELP = "simulate a session with known truth (rendered images, --points, or --intrinsics-set)"


def _int_list(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated capture indices, got {text!r}") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("out", help="new session folder (must not hold a session)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--points", action="store_true", help="corners only (corners.vnl), no images: fast")
    mode.add_argument("--intrinsics-set", action="store_true", help="varied-pose views for intrinsics calibration")
    p.add_argument("--preset", default=None,
                   help="paper-rig | paper-synthetic | small (default small), or a target row (docs/targets.md): paper-row | "
                        "small-row, or targets at two depths (docs/error-motions.md): paper-two-depth | paper-one-plane; "
                        "with --planar: paper-planar | small-planar | paper-constellation")
    p.add_argument("--planar", action="store_true",
                   help="an XY gantry (docs/planar.md): a grid over both axes; with --points (default preset paper-planar)")
    p.add_argument("--grid", help="planar grid X0,Y0:X1,Y1:DX,DY in mm (default the preset's 15 x 9 at 10 mm)")
    p.add_argument("--squareness-urad", type=float_range(-1e5, 1e5), help="planar: the gantry's squareness error (default 150)")
    p.add_argument("--rig", help="rig description JSON (board, intrinsics, camera pose, stage errors, plan, noise, outliers)")
    p.add_argument("--write-rig", action="store_true", help="write the preset's rig description to OUT (a .json file) and stop")
    p.add_argument("--seed", type=nonnegative_int, default=0)
    p.add_argument("--realism", choices=("off", "on", "strong"), default="off",
                   help="rendered sessions and intrinsics sets: a true lens with rational and thin-prism terms (on "
                        "~0.04 px, strong ~0.2 px beyond the 5-coefficient fit), prints off scale and bowed, blur and "
                        "noise varying over the image (docs/validation.md); default off")
    p.add_argument("--noise-px", type=nonnegative_finite, help="corner noise sigma, px (points mode)")
    p.add_argument("--views", type=int_range(3, 10000), default=20, help="views of an intrinsics set (default 20)")
    p.add_argument("--directions", choices=("+", "-", "both"), help="override the plan's directions")
    p.add_argument("--runs", type=int_range(1, 1000), help="override the plan's number of runs")
    p.add_argument("--stops", type=int_range(2, 100000), help="override the number of targets (same step)")
    p.add_argument("--replaced", type=_int_list, default=(), help="capture indices whose image is swapped for another position's")
    p.add_argument("--bumped", type=_int_list, default=(), help="capture indices where the camera is knocked")
    p.add_argument("--missing-fraction", type=float_range(0.0, 0.9), default=0.0, help="fraction of corners dropped at random")
    p.add_argument("--spec", metavar="SPEC", help="stage data sheet into session.json (as lps capture --spec): a preset "
                   "or accuracy=UM,repeatability=UM,straightness=UM,min_step=UM,settling=S")
    from lps_gui.cli.capture.asme_test import add_test_arguments

    add_test_arguments(p)


def build_spec(args: argparse.Namespace):
    from dataclasses import replace

    from lps_gui.core.truth.simulate import preset

    if args.rig:
        from lps_gui.core.truth.simulate import spec_from_dict
        from lps_gui.io.jsonfile import read_json

        spec = spec_from_dict(read_json(args.rig, "rig description"), args.rig)
    else:
        from lps_gui.cli.capture.asme_test import TEST_PRESET

        spec = preset(args.preset or (TEST_PRESET if getattr(args, "test", None) else "small"), seed=args.seed)
    plan = spec.plan
    if getattr(args, "test", None):
        from lps_gui.cli.capture.asme_test import test_plan_fields

        t = plan.targets()
        plan = replace(plan, **test_plan_fields(args, float(t[0]), float(t[-1])))
    if args.directions:
        plan = replace(plan, directions=args.directions)
    if args.runs:
        plan = replace(plan, runs=args.runs)
    if args.stops:
        plan = replace(plan, stop_mm=plan.start_mm + (args.stops - 1) * plan.step_mm)
    if spec.layout is not None and plan != spec.plan:  # a row faces the middle of its travel: build it for the new plan
        from lps_gui.core.truth.simulate import PRESETS

        spec = PRESETS[spec.name](seed=args.seed, plan=plan)
    overrides = {"plan": plan}
    if args.replaced or not args.rig:
        overrides["replaced_views"] = tuple(args.replaced)
    if args.bumped or not args.rig:
        overrides["bumped_views"] = tuple(args.bumped)
    if args.missing_fraction or not args.rig:
        overrides["missing_fraction"] = args.missing_fraction
    if args.rig and args.seed:
        overrides["seed"] = args.seed
    if args.noise_px is not None:
        overrides["noise_px"] = args.noise_px
    if getattr(args, "realism", "off") != "off":
        from lps_gui.core.truth.realism import realism_named
        from lps_gui.errors import InputError

        if args.points:
            raise InputError("simulate --realism: the realism is of rendered images (lens, prints, blur); drop --points")
        overrides["realism"] = realism_named(args.realism)
    spec = replace(spec, **overrides)
    _check_noise(spec, "--noise-px" if args.noise_px is not None else (args.rig or "preset"))
    from lps_gui.cli.capture.asme_test import simulated_stage

    spec, ringing = simulated_stage(args, spec)
    if ringing is None:
        return spec
    from lps_gui.cli.capture.asme_test import SIM_FRAME_S

    return replace(spec, vibration=ringing, frame_interval_s=SIM_FRAME_S)


def _record_setup(args: argparse.Namespace, session) -> None:
    """--spec and --test into session.json (what lps capture records for the same switches: one SessionSetup)."""
    from lps_gui.capture.setup import apply_setup
    from lps_gui.cli.capture.setup import setup_meta

    apply_setup(session, setup_meta(args))


def _check_noise(spec, source: str) -> None:
    """Noise sigmas and the outlier fraction must be non-negative numbers (numpy raises "scale < 0" otherwise)."""
    from lps_gui.errors import InputError

    for name in ("noise_px", "noise_clip_px", "missing_fraction"):
        value = getattr(spec, name, None)
        if value is not None and not float(value) >= 0:
            raise InputError(f"{source}: {name} is {value}; give 0 or more")


def check_new_folder(out, option: str) -> None:
    """A set of views goes into a new or empty folder: its names (view_000.png, poses_truth.json, board.json)
    would replace another set's or a session's files."""
    from lps_gui.errors import InputError

    if out.is_symlink() or (out.exists() and (not out.is_dir() or any(out.iterdir()))):
        raise InputError(f"{option} {out}: exists and is not an empty folder; give a new folder (nothing of "
                         "another set or session is replaced)")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from lps_gui.cli.progress_bar import ProgressBar

    out = Path(args.out)
    if args.planar:
        return _run_planar(args, out)
    spec = build_spec(args)
    if args.write_rig:
        from lps_gui.core.truth.simulate import spec_to_dict
        from lps_gui.errors import InputError

        if spec.layout is not None:
            raise InputError(f"simulate --write-rig: preset {spec.name} is a row of targets, which a rig description "
                             "does not hold yet; use --preset with --stops, --noise-px and --seed")
        from lps_gui.cli.out_path import check_out_file
        from lps_gui.io.jsonfile import write_json

        write_json(check_out_file(out, option="simulate --write-rig"), spec_to_dict(spec))
        print(f"wrote the rig description of preset {spec.name} to {out}; edit it and pass --rig {out}")
        return 0
    if args.intrinsics_set:
        from lps_gui.sim.images import simulate_intrinsics_set

        check_new_folder(out, "simulate --intrinsics-set")
        real = spec.camera_realism()  # the same true lens and print as a rendered session of this seed
        paths = simulate_intrinsics_set(out, spec.rig.board, spec.rig.intrinsics, n_views=args.views, seed=args.seed,
                                        progress=ProgressBar("render"), lens=real.get("lens"),
                                        printed=real.get("printed") if spec.layout is None else None)
        print(f"wrote {len(paths)} calibration views to {out}")
        return 0
    if args.points:
        from lps_gui.sim.points import simulate_point_session

        session = simulate_point_session(spec, out)
        _record_setup(args, session)
        print(f"wrote point-level session ({spec.plan.n_frames()} views, preset {spec.name}) to {session.folder}")
        return 0
    from lps_gui.sim.images import simulate_image_session

    session = simulate_image_session(spec, out, progress=ProgressBar("render"))
    _record_setup(args, session)
    print(f"wrote rendered session ({spec.plan.n_frames()} images, preset {spec.name}) to {session.folder}")
    return 0


def build_planar_spec(args: argparse.Namespace):
    """The planar preset with the command line's overrides."""
    from dataclasses import replace

    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.truth.simulate import paper_planar_errors, preset
    from lps_gui.errors import InputError

    spec = preset(args.preset or "paper-planar", planar=True, seed=args.seed)
    plan = spec.plan
    if args.grid:
        try:
            (x0, y0), (x1, y1), (dx, dy) = (tuple(float(v) for v in part.split(",")) for part in args.grid.split(":"))
        except ValueError:
            raise InputError(f"simulate: --grid {args.grid!r} is not X0,Y0:X1,Y1:DX,DY (mm)") from None
        plan = Plan.xy(start_mm=(x0, y0), stop_mm=(x1, y1), step_mm=(dx, dy))
    if args.directions:
        plan = replace(plan, directions=args.directions)
    if args.runs:
        plan = replace(plan, runs=args.runs)
    overrides = {"plan": plan, "replaced_views": tuple(args.replaced), "bumped_views": tuple(args.bumped),
                 "missing_fraction": args.missing_fraction}
    if args.noise_px is not None:
        overrides["noise_px"] = args.noise_px
    if args.squareness_urad is not None:
        overrides["rig"] = replace(spec.rig, errors=replace(spec.rig.errors, squareness_urad=args.squareness_urad))
    elif spec.name == "paper-planar":
        overrides["rig"] = replace(spec.rig, errors=paper_planar_errors())
    if args.grid:  # re-centre the camera on the new grid
        from lps_gui.core.truth.simulate import PLANAR_PRESETS

        base = PLANAR_PRESETS[spec.name](seed=args.seed, plan=plan, errors=overrides.get("rig", spec.rig).errors)
        overrides["rig"] = base.rig
    return replace(spec, **overrides)


def _run_planar(args: argparse.Namespace, out) -> int:
    from lps_gui.errors import InputError

    if getattr(args, "test", None):
        raise InputError("--test: the ASME B5.64 tests are single-axis tests; drop --planar")
    if not args.points:
        raise InputError("simulate --planar: only --points sessions yet; rendered planar images come from "
                         "`lps capture` on the simulated gantry")
    spec = build_planar_spec(args)
    from lps_gui.sim.points import simulate_point_session

    session = simulate_point_session(spec, out)
    print(f"wrote planar point-level session ({spec.plan.n_frames()} views on X,Y, preset {spec.name}) to {session.folder}")
    return 0
