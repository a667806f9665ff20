"""The ``lps`` command: one sub-command per module in this package.

Command modules import only argparse at module level (heavy imports live in
their ``run``), so ``--help`` is instant. Each command module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int``. A user error prints one line and exits 2; a bug prints
one line and leaves the traceback in the log file.
"""
from __future__ import annotations

import argparse
import errno
import logging
import os
import sys
from typing import NoReturn

from lps_gui.cli import (
    compare,
    compensate,
    demo,
    detect,
    emulate,
    emulate_grbl,
    estimate,
    export,
    import_images,
    intrinsics,
    lightfield,
    make_targets,
    report,
    simulate,
)
from lps_gui.cli.capture import command as capture
from lps_gui.cli.plan_rig import command as plan_rig

COMMANDS = {
    "demo": demo,
    "simulate": simulate,
    "detect": detect,
    "intrinsics": intrinsics,
    "estimate": estimate,
    "report": report,
    "capture": capture,
    "import": import_images,
    "emulate": emulate,
    "emulate-grbl": emulate_grbl,  # the same as `lps emulate grbl`
    "plan-rig": plan_rig,
    "compensate": compensate,
    "export": export,
    "lightfield": lightfield,
    "compare": compare,
    "make-targets": make_targets,
}


class _VersionAction(argparse.Action):
    """``--version``, with the version looked up only when asked for (every other command starts without importlib.metadata)."""

    def __init__(self, option_strings: list[str], dest: str = argparse.SUPPRESS, default: str = argparse.SUPPRESS,
                 help: str = "show program's version number and exit") -> None:
        super().__init__(option_strings=option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: object,
                 option_string: str | None = None) -> None:
        from lps_gui import __version__

        sys.stdout.write(f"lps-calib {__version__}\n")
        parser.exit()


class _OneLineErrors(argparse.ArgumentParser):
    """A refused option is one line like every other user error (argparse would print the usage first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineErrors(
        prog="lps",
        description="Measure a linear positioning stage from a camera's images of a chessboard.",
    )
    parser.add_argument("--version", action=_VersionAction)
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages to stderr")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in COMMANDS.items():
        p = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_module=module)
    return parser


def main(argv: list[str] | None = None) -> int:
    from lps_gui.blas_threads import limit_blas_threads

    limit_blas_threads()  # before anything imports numpy
    from lps_gui.gc_tuning import collect_again, freeze_for_exit


    collect_again()  # an earlier main() in this process froze its objects for its exit
    try:
        return _main(argv)
    finally:
        freeze_for_exit()  # the process usually ends now: its exit skips collecting everything alive


def _main(argv: list[str] | None) -> int:
    from lps_gui.allocator import tune_allocator
    from lps_gui.errors import LpsError

    parser = build_parser()
    args = parser.parse_args(argv)
    tune_allocator()
    if not getattr(args, "command", None):
        parser.print_help()
        return 2
    from lps_gui.cli.log_file import process_log_handler

    handler, log_where = process_log_handler()
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(asctime)s %(name)s %(levelname)s %(message)s",
        handlers=[handler] + ([logging.StreamHandler()] if args.verbose else []),
    )
    try:
        check_no_nul(args)
        return int(args._module.run(args) or 0)
    except LpsError as exc:
        logging.getLogger("lps").info("user error", exc_info=True)
        print(f"lps {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"lps {args.command}: interrupted; what was finished is kept", file=sys.stderr)
        return 130
    except OSError as exc:
        if exc.errno not in _STORAGE_ERRNOS:
            return _bug(args.command, exc, log_where)
        logging.getLogger("lps").info("storage error", exc_info=True)  # a full disk in a writer not yet checked
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"lps {args.command}: error: {where}cannot write ({exc.strerror}); free disk space or make the folder "
              "writable and run again", file=sys.stderr)
        return 2
    except Exception as exc:  # a bug: one line here, the traceback in the log
        return _bug(args.command, exc, log_where)


def check_no_nul(args: argparse.Namespace) -> None:
    """InputError naming the option whose value holds a NUL byte: no file name can (os calls raise ValueError)."""
    from lps_gui.errors import InputError

    for name, value in vars(args).items():
        values = value if isinstance(value, (list, tuple)) else [value]
        if any(isinstance(v, (str, os.PathLike)) and "\x00" in os.fspath(v) for v in values):
            raise InputError(f"argument {name.replace('_', '-')}: holds a NUL byte, which no file name or setting can; "
                             "check the command line")


def _bug(command: str, exc: BaseException, log_where: str) -> int:
    """A bug: one line here, the traceback in the log."""
    logging.getLogger("lps").error("unexpected failure", exc_info=exc)
    print(f"lps {command}: internal error: {type(exc).__name__}: {exc} (traceback in {log_where})", file=sys.stderr)
    return 1


_STORAGE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EIO, errno.EFBIG}


if __name__ == "__main__":
    sys.exit(main())
