"""Where the ``lps`` command writes its log: the user's own state folder, never a shared fixed path.

``$XDG_STATE_HOME/lps-calib/lps.log`` (default ``~/.local/state/lps-calib``),
the folder created 0700 and the file opened without following a symlink,
so another user cannot redirect or read the log (a fixed name in /tmp can
be pre-created as a symlink or a folder by anyone). When the log cannot be
opened, the command still runs and says so instead of dying.
"""
from __future__ import annotations

import functools
import logging
import os
from pathlib import Path

LOG_NAME = "lps.log"


def log_dir() -> Path:
    base = os.environ.get("XDG_STATE_HOME")
    if not base or not os.path.isabs(base):  # the XDG rule: a relative value is ignored
        base = str(Path.home() / ".local" / "state")
    return Path(base) / "lps-calib"


def log_path() -> Path:
    return log_dir() / LOG_NAME


def open_log_handler() -> tuple[logging.Handler, str]:
    """(a handler on the log file, its path) or (a NullHandler, why there is no log)."""
    folder = log_dir()
    path = folder / LOG_NAME
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if folder.is_symlink() or not folder.is_dir():
            raise OSError(f"{folder} is not a folder of its own")
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o600)
    except OSError as exc:
        return logging.NullHandler(), f"no log file: {path}: {exc.strerror or exc}"
    stream = os.fdopen(fd, "a", encoding="utf-8")
    return logging.StreamHandler(stream), str(path)


@functools.lru_cache(maxsize=1)
def process_log_handler() -> tuple[logging.Handler, str]:
    """:func:`open_log_handler` once per process (``main`` may run many times in one, e.g. in tests)."""
    return open_log_handler()
