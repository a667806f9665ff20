"""`lps capture` switches for what a report needs besides images: specification, environment, identification.

The switches are the fields of :mod:`lps_gui.io.setup_fields`; what they mean and how they are checked
is :class:`lps_gui.capture.setup.SessionSetup` (the GUI's capture panel fills the same), written into
session.json (``stage_spec``, ``environment``, ``asme_test``, ``identification``) when a session is
created or resumed, so nobody edits session.json by hand.
``--iso-plan`` replaces the targets by the ISO 230-2 preset (5 runs both ways,
non-uniform spacing; :mod:`lps_gui.core.planning.presets`).
"""
from __future__ import annotations

import argparse
from typing import Any

from typing import TYPE_CHECKING

from lps_gui.cli.option_types import finite, int_range, positive_finite
from lps_gui.io.setup_fields import ENV_FIELDS, ID_FIELDS

if TYPE_CHECKING:  # `lps capture --help` imports no numpy
    from lps_gui.capture.setup import SessionSetup


def add_setup_arguments(p: argparse.ArgumentParser, iso_plan: bool = True) -> None:
    """The report's switches, in their own help groups (``iso_plan``: with the ISO 230-2 plan's, for a capture)."""
    from lps_gui.core.planning.presets import SPEC_PRESETS

    r = p.add_argument_group("specification and ISO 230-2 plan" if iso_plan else "specification")
    r.add_argument("--spec", metavar="SPEC", help=f"stage data sheet: a preset ({', '.join(SPEC_PRESETS)}; paper = "
                   "its Table 1) or accuracy=UM,repeatability=UM,straightness=UM")
    if iso_plan:
        _add_iso_plan_arguments(r)
    e = p.add_argument_group("environment (session.json 'environment')")
    for f in ENV_FIELDS:
        e.add_argument(f.flag, type=finite, dest=f"env_{f.key}", metavar="X", help=f.help)
    e.add_argument("--env-notes", dest="env_notes", metavar="TEXT", help="free text: thermometer, where it was, ...")
    i = p.add_argument_group("identification (printed on the report)")
    for f in ID_FIELDS:
        i.add_argument(f.flag, dest=f"id_{f.key}", metavar="TEXT", help=f.help)


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


def session_setup(args: argparse.Namespace) -> "SessionSetup":
    """The operator's set-up of the switches given (``lps_gui.capture.setup``: the GUI's form builds the same)."""
    from lps_gui.capture.setup import SessionSetup

    return SessionSetup(
        spec=getattr(args, "spec", None),
        environment={f.key: getattr(args, f"env_{f.key}", None) for f in ENV_FIELDS},
        env_notes=getattr(args, "env_notes", None) or "",
        identification={f.key: getattr(args, f"id_{f.key}", None) for f in ID_FIELDS},
        test=getattr(args, "test", None), test_step_um=getattr(args, "test_step_um", None),
        test_band_um=getattr(args, "test_band_um", None), where="environment switches")


def setup_meta(args: argparse.Namespace) -> dict[str, Any]:
    """session.json entries from the switches given (only those given), checked before any device opens."""
    return session_setup(args).meta()
