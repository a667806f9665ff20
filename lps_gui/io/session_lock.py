"""One writer per session folder: an advisory fcntl lock on ``SESSION/.lock``.

Capture, resume, detection and estimation take the lock before they write
into a session, so two of them never interleave lines in captures.jsonl or
replace each other's results. The lock file records who holds it (pid,
host, command, since) so the second process can say so. The kernel drops
the lock when its holder exits, however it exits: a stale lock file (after
a kill) never blocks anyone. The holder deletes the file on release; a
process that locked a file just deleted sees its inode gone and retries.
"""
from __future__ import annotations

import errno
import json
import os
import socket
import sys
import threading
import time
from pathlib import Path
from types import TracebackType

from lps_gui.errors import InputError, LpsError
from lps_gui.io.atomic import remove_orphan_temps
from lps_gui.io.file_set import recover_file_set

LOCK_FILE = ".lock"


class SessionBusy(InputError):
    """Another process holds the session's lock."""


def _holder_text(raw: bytes) -> str:
    try:
        info = json.loads(raw.decode("utf-8"))
        return f"pid {info['pid']} on {info['host']} ({info['command']}, since {info['since']})"
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        return "another process"


def _inside(folder: Path, place: Path) -> bool:
    """``place`` is a real folder inside ``folder`` (no link on the way out)."""
    try:
        return not place.is_symlink() and place.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):
        return False


def tidy_after_kill(folder: Path) -> None:
    """What a killed writer left: finish its journaled result commit, delete its temp files.

    Run by whoever takes the lock (no other writer of the session runs then; a live process's temp files
    are kept by pid all the same).
    """
    places = [folder, folder / "images", folder / "results"]
    try:
        places += [p for p in (folder / "results").iterdir() if p.is_dir() and not p.is_symlink()]
    except OSError:
        pass
    for place in places:
        if place != folder and not _inside(folder, place):  # images/ or results/ linked elsewhere: not ours to tidy
            continue
        try:
            recover_file_set(place)
        except LpsError:  # a read-only folder: the next writable run finishes it
            pass
        remove_orphan_temps(place)


class SessionLock:
    """``with SessionLock(folder, "lps estimate"):`` holds the folder's lock or raises :class:`SessionBusy`.

    Re-entrant within one thread (the CLI holds it for a whole command and
    the pipeline takes it again around its write); another thread of the
    same process is refused like another process (flock locks belong to
    the open file, not the process).
    """

    _held: dict[tuple[str, int], int] = {}  # (resolved folder, thread) -> depth

    def __init__(self, folder: Path | str, command: str | None = None):
        self.folder = Path(folder)
        self.command = command or " ".join(["lps", *sys.argv[1:]])[:200]
        self._fd: int | None = None
        self._key = (str(self.folder.resolve()), threading.get_ident())

    def __enter__(self) -> "SessionLock":
        import fcntl

        if self._held.get(self._key):
            self._held[self._key] += 1
            return self
        path = self.folder / LOCK_FILE
        for _attempt in range(20):
            fd = self._open(path)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                holder = _holder_text(os.pread(fd, 4096, 0))
                os.close(fd)
                if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise SessionBusy(f"{self.folder}: session is in use by {holder}; wait for it to finish "
                                      "(or stop it) and run again") from None
                raise InputError(f"{path}: cannot lock the session ({exc.strerror})") from None
            try:
                same = os.stat(path, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)  # the holder released and deleted it meanwhile: lock the new file
        else:
            raise InputError(f"{path}: the session lock keeps changing; run again")
        info = {"pid": os.getpid(), "host": socket.gethostname(), "command": self.command,
                "since": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, json.dumps(info).encode("utf-8"), 0)
        except OSError:  # a full disk must not keep the lock from working: the holder is then unnamed
            pass
        self._fd = fd
        self._held[self._key] = 1
        tidy_after_kill(self.folder)
        return self

    def _open(self, path: Path) -> int:
        try:
            return os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise InputError(f"{path}: is a symbolic link; remove it") from None
            if exc.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
                raise InputError(f"{self.folder}: session folder is read-only ({exc.strerror}); "
                                 "copy the session to a writable folder") from None
            if exc.errno == errno.ENOENT:
                raise InputError(f"{self.folder}: session folder not found; check the path") from None
            raise InputError(f"{path}: cannot create the session lock ({exc.strerror})") from None

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        import fcntl

        depth = self._held.get(self._key, 0) - 1
        if depth > 0:
            self._held[self._key] = depth
            return
        self._held.pop(self._key, None)
        if self._fd is not None:
            try:
                os.unlink(self.folder / LOCK_FILE)  # while still locked: nobody can hold this inode now
            except OSError:
                pass
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None
