"""User-facing errors.

Every failure a user can cause (a wrong file, a board not found, a port that
vanished) is raised as an :class:`LpsError` whose message is one line naming
the thing and what to do. The CLI and GUI show that line; tracebacks go to the
log. Layer-neutral: every package may import this module.
"""
from __future__ import annotations


class LpsError(Exception):
    """An error with a message a user can act on (one line, no traceback)."""


class InputError(LpsError):
    """A file, argument or data set is unusable as given."""


class DegenerateGeometryError(LpsError):
    """The views do not determine the unknowns (too few, all at one place...)."""


class HardwareError(LpsError):
    """A stage or camera failed, timed out or disappeared."""


class Cancelled(LpsError):
    """Long work stopped on request; what was done so far is kept."""


class StorageError(LpsError):
    """A file could not be written completely (disk full, read-only folder); the old file is kept."""
