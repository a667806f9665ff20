"""`lps capture` switches for what a report needs besides images: specification, environment, identification.

They go into session.json (``stage_spec``, ``environment``, ``identification``)
when a session is created or resumed, so nobody edits session.json by hand.
``--iso-plan`` replaces the targets by the ISO 230-2 preset (5 runs both ways,
non-uniform spacing; :mod:`lps_gui.core.planning.presets`).
"""
from __future__ import annotations

import argparse
from typing import Any

from lps_gui.cli.option_types import finite, int_range, positive_finite

ENV_SWITCHES = (("--board-temp", "board_temperature_c", "board temperature, deg C (corrects the length scale to 20 C)"),
                ("--board-cte", "board_cte_ppm_per_k", "board expansion coefficient, ppm/K (e.g. 23 aluminium, 8 glass)"),
                ("--square-u", "square_mm_uncertainty_um", "standard uncertainty of the board's square size, µm (certificate)"),
                ("--stage-temp", "stage_temperature_c", "stage temperature, deg C"),
                ("--stage-cte", "stage_cte_ppm_per_k", "stage scale expansion coefficient, ppm/K (e.g. 11.5 steel screw)"),
                ("--temp-u", "temperature_uncertainty_k", "standard uncertainty of the thermometers, K (default 0.5)"))
ID_SWITCHES = (("--operator", "operator"), ("--customer", "customer"), ("--stage-model", "stage_model"),
               ("--serial", "stage_serial"), ("--controller-serial", "controller_serial"), ("--location", "location"))


def _id_switches() -> tuple[tuple[str, str], ...]:
    """The identification switches: who and where, then the signing block's (lps_gui.report.pages.signing)."""
    from lps_gui.report.pages.signing import SIGNING_FIELDS

    return ID_SWITCHES + tuple((flag, key) for key, flag, _ in SIGNING_FIELDS)


def add_setup_arguments(p: argparse.ArgumentParser, iso_plan: bool = True) -> None:
    """The report's switches, in their own help groups (``iso_plan``: with the ISO 230-2 plan's, for a capture)."""
    from lps_gui.core.planning.presets import SPEC_PRESETS

    r = p.add_argument_group("specification and ISO 230-2 plan" if iso_plan else "specification")
    r.add_argument("--spec", metavar="SPEC", help=f"stage data sheet: a preset ({', '.join(SPEC_PRESETS)}; paper = "
                   "its Table 1) or accuracy=UM,repeatability=UM,straightness=UM")
    if iso_plan:
        _add_iso_plan_arguments(r)
    e = p.add_argument_group("environment (session.json 'environment')")
    for flag, key, text in ENV_SWITCHES:
        e.add_argument(flag, type=finite, dest=f"env_{key}", metavar="X", help=text)
    e.add_argument("--env-notes", dest="env_notes", metavar="TEXT", help="free text: thermometer, where it was, ...")
    i = p.add_argument_group("identification (printed on the report)")
    from lps_gui.report.pages.signing import SIGNING_FIELDS

    helps = {key: text for key, _, text in SIGNING_FIELDS}
    for flag, key in _id_switches():
        i.add_argument(flag, dest=f"id_{key}", metavar="TEXT", help=helps.get(key, key.replace("_", " ")))


def _add_iso_plan_arguments(r: argparse._ArgumentGroup) -> None:
    r.add_argument("--iso-plan", action="store_true", help="ISO 230-2 plan: 5 runs both directions over non-uniform "
                   "targets between --start and --stop")
    r.add_argument("--iso-targets", type=int_range(5, 10000), metavar="N", help="number of targets of --iso-plan (default 5 per metre, min 5)")
    r.add_argument("--pitch", type=positive_finite, metavar="MM", help="lead-screw pitch for --iso-plan: targets spread over its phase")


def iso_plan_fields(args: argparse.Namespace, base: Any) -> dict[str, Any]:
    """Plan fields of ``--iso-plan`` (empty without it); the range from --start/--stop or the base plan."""
    if not getattr(args, "iso_plan", False):
        return {}
    from lps_gui.core.planning.presets import iso230_plan_fields
    from lps_gui.errors import InputError

    start = args.start_mm if args.start_mm is not None else getattr(base, "start_mm", None)
    stop = args.stop_mm if args.stop_mm is not None else getattr(base, "stop_mm", None)
    if start is None or stop is None:
        raise InputError("--iso-plan: give --start and --stop (mm) of the travel to test")
    if args.targets:
        raise InputError("--iso-plan chooses the targets; drop --targets (or drop --iso-plan)")
    return iso230_plan_fields(float(start), float(stop), args.iso_targets, args.pitch)


def setup_meta(args: argparse.Namespace) -> dict[str, Any]:
    """session.json entries from the switches given (only those given)."""
    from lps_gui.core.metrology.environment import Environment
    from lps_gui.core.planning.presets import parse_spec

    out: dict[str, Any] = {}
    if getattr(args, "spec", None):
        out["stage_spec"] = parse_spec(args.spec)
    env = {key: getattr(args, f"env_{key}") for _, key, _ in ENV_SWITCHES if getattr(args, f"env_{key}", None) is not None}
    if getattr(args, "env_notes", None):
        env["notes"] = args.env_notes
    if env:
        out["environment"] = Environment.from_dict(env, "environment switches").to_dict()
    from lps_gui.cli.capture.asme_test import test_record

    if test_record(args):
        out["asme_test"] = test_record(args)
    ident = {key: getattr(args, f"id_{key}") for _, key in _id_switches() if getattr(args, f"id_{key}", None)}
    if ident:
        out["identification"] = ident
    return out


def apply_setup(session: Any, extra: dict[str, Any]) -> None:
    """Merge :func:`setup_meta` into session.json (environment and identification key by key) and save it."""
    if not extra:
        return
    for key, value in extra.items():
        if isinstance(value, dict) and key != "stage_spec":
            session.meta[key] = {**(session.meta.get(key) or {}), **value}
        else:
            session.meta[key] = value
    session.save_meta()
