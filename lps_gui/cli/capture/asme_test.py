"""`--test min-step|settling`: the ASME B5.64 test plans for `lps capture` and `lps simulate`.

The switch replaces the targets by the test's preset (:mod:`lps_gui.core.planning.presets`)
over the travel (--start/--stop or the preset's), records the test in
session.json ``asme_test`` (what `lps estimate` computes for it, docs/asme-b5.64.md)
and, on a simulated rig, gives the stage what the test looks for: a dead
band (--dead-band-um) and the ringing after a move (--ringing).
"""
from __future__ import annotations

import argparse
from dataclasses import replace
from typing import Any

from lps_gui.cli.option_types import int_range, nonnegative_finite, positive_finite

SIM_FRAME_S = 0.01  # the simulated camera's frame time in a settling test (100 frames per second)
TEST_PRESET = "paper-closeup"  # the simulated set-up of the tests when no --preset is given (simulate)


def _ringing(text: str):
    from lps_gui.core.truth.stage_errors import Vibration

    try:
        amp, freq, decay = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected AMP_UM,FREQ_HZ,DECAY_S, e.g. 50,8,0.25, got {text!r}") from None
    if not (amp > 0 and freq > 0 and decay > 0):
        raise argparse.ArgumentTypeError(f"--ringing {text}: amplitude, frequency and decay must be positive")
    return Vibration(amplitude_um=amp, frequency_hz=freq, decay_s=decay)


def add_test_arguments(p: argparse.ArgumentParser) -> None:
    """The test switches, in their own help group."""
    from lps_gui.core.planning.presets import (
        ASME_TESTS,
        MIN_STEP_FRAMES,
        MIN_STEP_LOCATIONS,
        MIN_STEP_UM,
        SETTLING_BAND_UM,
        SETTLING_FRAMES,
    )

    g = p.add_argument_group("ASME B5.64 tests (docs/asme-b5.64.md)")
    g.add_argument("--test", choices=ASME_TESTS, help=f"min-step: incremental steps ({MIN_STEP_UM:g} um) forward and "
                   f"back at {MIN_STEP_LOCATIONS} places, {MIN_STEP_FRAMES} frames per stop averaged; settling: "
                   f"{SETTLING_FRAMES} frames back to back after each move, the time to settle in a band")
    g.add_argument("--test-step-um", type=positive_finite, metavar="UM", help=f"min-step: the commanded step (default {MIN_STEP_UM:g})")
    g.add_argument("--test-steps", type=int_range(1, 1000), metavar="N", help="min-step: steps per place (default 10)")
    g.add_argument("--test-band-um", type=positive_finite, metavar="UM",
                   help=f"settling: settled within +-UM of rest (default {SETTLING_BAND_UM:g})")
    g.add_argument("--dead-band-um", type=nonnegative_finite, metavar="UM", help="simulated stage: stick-slip, a move "
                   "shorter than UM does not move the carriage")
    g.add_argument("--ringing", type=_ringing, metavar="AMP,FREQ,DECAY", help="simulated stage: rings after each move "
                   "(um, Hz, s; default with --test settling 50,8,0.25)")


def test_plan_fields(args: argparse.Namespace, start_mm: float | None, stop_mm: float | None) -> dict[str, Any]:
    """Plan fields of ``--test`` over [start, stop] (empty without it); --frames and --settle still override."""
    test = getattr(args, "test", None)
    if not test:
        return {}
    from lps_gui.capture.setup import asme_plan_fields
    from lps_gui.errors import InputError

    if getattr(args, "iso_plan", False):
        raise InputError("--test and --iso-plan are two plans; give one")
    if getattr(args, "targets", None):
        raise InputError(f"--test {test} chooses the targets; drop --targets")
    if start_mm is None or stop_mm is None:
        raise InputError(f"--test {test}: give --start and --stop (mm) of the travel to test")
    fields = asme_plan_fields(test, start_mm, stop_mm, args.test_step_um, args.test_steps)
    for key in ("frames_per_stop", "settle_s"):  # the operator's switches win
        if getattr(args, key, None) is not None:
            fields.pop(key, None)
    return fields


def test_record(args: argparse.Namespace) -> dict[str, Any] | None:
    """session.json ``asme_test`` of the switches (None without --test)."""
    from lps_gui.cli.capture.setup import session_setup

    return session_setup(args).test_record()


def simulated_stage(args: argparse.Namespace, spec: Any) -> tuple[Any, Any]:
    """(spec with the dead band in its stage errors, the ringing or None) for a simulated rig."""
    from lps_gui.core.truth.stage_errors import Vibration

    if getattr(args, "dead_band_um", None):
        spec = replace(spec, rig=replace(spec.rig, errors=replace(spec.rig.errors, dead_band_um=args.dead_band_um)))
    ringing = getattr(args, "ringing", None)
    if ringing is None and getattr(args, "test", None) == "settling":
        ringing = Vibration()
    return spec, ringing


def simulated_rig_options(ringing: Any) -> dict[str, Any]:
    """make_simulated_rig's options of a ringing stage: the ringing, and a camera whose frames take
    ``SIM_FRAME_S`` each (a simulated camera otherwise grabs every frame at one instant)."""
    return {} if ringing is None else {"vibration": ringing, "exposure_s": SIM_FRAME_S}
