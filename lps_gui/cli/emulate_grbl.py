"""``lps emulate-grbl``: a GRBL 1.1 controller on a pseudo-terminal, over the simulated stage.

Prints the pty path on the first line of stdout (connect any GRBL sender to
it, e.g. ``lps capture --stage grbl:/dev/pts/5``), then serves until Ctrl-C.
Fault switches inject what goes wrong with real hardware.
"""
from __future__ import annotations

import argparse
from typing import Any

from lps_gui.cli.option_types import float_range

HELP = "serve a GRBL 1.1 emulator on a pseudo-terminal (prints its path) until Ctrl-C"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--time-scale", type=float_range(1e-3, 1e6), default=1.0, help="simulated seconds per real second (default 1: GRBL's own timing)")
    parser.add_argument("--travel", type=float, nargs=2, default=(-5.0, 500.0), metavar=("MIN_MM", "MAX_MM"), help="soft-limit travel in work coordinates")
    parser.add_argument("--max-rate", type=float, default=3000.0, help="max rate $110 in mm/min")
    parser.add_argument("--accel", type=float, default=200.0, help="acceleration $120 in mm/s^2")
    parser.add_argument("--start", type=float, default=0.0, help="carriage position at power-up (mm)")
    parser.add_argument("--homing-required", action="store_true", help="start locked in Alarm until $H or $X, even with --no-homing-lock")
    parser.add_argument("--no-homing-lock", action="store_true",
                        help="build without HOMING_INIT_LOCK ([OPT:VL]): power up Idle although $22=1 (stock 1.1h powers up in Alarm)")
    parser.add_argument("--errors", choices=("none", "paper"), default="none", help="true-position error model of the carriage")
    parser.add_argument("--seed", type=int, default=0, help="seed of the repeatability draws")
    faults = parser.add_argument_group("fault injection")
    faults.add_argument("--drop-after-lines", type=int, metavar="N", help="close the port after N received lines (vanished USB cable)")
    faults.add_argument("--alarm-mid-move", type=int, choices=range(1, 11), metavar="CODE",
                        help="raise ALARM:CODE (1-10, GRBL 1.1's alarms) half-way through the first move (1 = hard limit)")
    faults.add_argument("--error-every", type=int, default=0, metavar="N", help="answer every Nth command with an error instead of executing it")
    faults.add_argument("--error-code", type=int, default=20, metavar="CODE", help="the error code of --error-every (default 20)")
    faults.add_argument("--reply-delay", type=float, default=0.0, metavar="S", help="delay every reply by S seconds (slow replies)")
    faults.add_argument("--fail-homing", type=int, nargs="?", const=8, choices=(8, 9), metavar="CODE",
                        help="every $H fails half-way with ALARM:CODE (8 pull-off, the default; 9 switch not found), then ok and a reset")
    faults.add_argument("--garbage-every", type=int, default=0, metavar="N", help="send a line of garbage bytes before every Nth message")
    link = parser.add_argument_group("link timing (GRBL: the races a real board's USB link and boot produce)")
    link.add_argument("--line-latency", type=float_range(0.0, 1000.0), default=0.0, metavar="MS",
                      help="deliver every reply line MS milliseconds after the one before it, like a USB serial "
                           "adapter's latency timer (16 on FTDI chips): a report asked for before a real-time byte "
                           "can then arrive after it")
    link.add_argument("--boot-race", action="store_true",
                      help="boot as the port opens (an Arduino's DTR reset): the boot banner waits for the host's "
                           "first byte, and a reset byte sent during boot gives a second banner after it")


def run(args: argparse.Namespace) -> int:
    return serve(args, "grbl")


def build_emulator(args: argparse.Namespace, kind: str) -> Any:
    """The (not yet started) emulator of stage ``kind`` (a registry name) over the simulated stage the switches describe."""
    from lps_gui.errors import InputError
    from lps_gui.hardware.grbl.emulator import Faults
    from lps_gui.hardware.line_emulator import LinkFaults
    from lps_gui.hardware.registry import emulated_kinds
    from lps_gui.hardware.sim_stage import SimulatedStage

    lo, hi = args.travel
    if not lo < hi:
        raise InputError(f"--travel {lo:g} {hi:g}: MIN_MM must be below MAX_MM")
    if args.time_scale <= 0:
        raise InputError(f"--time-scale {args.time_scale:g}: must be positive")
    errors = None
    if args.errors == "paper":
        from lps_gui.core.truth.simulate import paper_stage_errors

        errors = paper_stage_errors()
    stage = SimulatedStage(
        errors=errors, seed=args.seed, travel_mm=(lo, hi), max_rate_mm_min=args.max_rate,
        accel_mm_s2=args.accel, homing_required=args.homing_required, start_mm=args.start,
    )
    link = {"drop_after_lines": args.drop_after_lines, "reply_delay_s": args.reply_delay, "garbage_every": args.garbage_every}
    faults: LinkFaults = LinkFaults(**link)
    options: dict[str, Any] = {}
    if kind == "grbl":  # GRBL's own fault switches, build option and link races
        faults = Faults(**link, alarm_mid_move=args.alarm_mid_move, error_every=args.error_every,
                        error_code=args.error_code, fail_homing=args.fail_homing)
        options = {"homing_init_lock": not args.no_homing_lock, "line_latency_s": args.line_latency / 1000.0,
                   "boot_race": args.boot_race}
    emulator = emulated_kinds()[kind].emulator
    assert emulator is not None  # emulated_kinds() lists only kinds with one
    return emulator()(stage, faults=faults, time_scale=args.time_scale, **options)


def serve(args: argparse.Namespace, kind: str) -> int:
    """Serve the emulator of stage ``kind`` (a registry name) over the simulated stage the switches describe."""
    import signal
    import sys
    import time

    from lps_gui.hardware.announce import announce

    emu = build_emulator(args, kind)
    stop: list[int] = []  # a plain flag: a handler calling Event.set() can deadlock on the lock wait() holds
    try:  # SIGTERM (a service manager, `kill`) stops as cleanly as Ctrl-C; set before the path is announced
        signal.signal(signal.SIGTERM, lambda signum, _frame: stop.append(signum))
    except ValueError:  # not the main thread (tests calling run() directly)
        pass
    withdraw = None
    try:
        path = emu.start()
        withdraw = announce(path, kind=kind)  # the GUI's stage list shows it
        print(path, flush=True)
        print(f"{kind} emulator on {path} (115200 baud, any rate works on a pty; --stage {kind}:{path}); Ctrl-C to stop",
              file=sys.stderr, flush=True)
        while not stop:
            time.sleep(0.2)
            if emu.dropped:
                print("emulator: connection dropped (fault injection); stopping", file=sys.stderr)
                break
            if not emu.running:  # the serving thread died: its error is in the log
                print("emulator: stopped unexpectedly (see the log)", file=sys.stderr)
                return 1
        if stop:
            print("emulator: stopped", file=sys.stderr)
    except KeyboardInterrupt:
        print("emulator: stopped", file=sys.stderr)
    finally:
        if withdraw is not None:
            withdraw()
        emu.stop()
    return 0
