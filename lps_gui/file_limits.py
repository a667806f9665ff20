"""Reading a file without being led elsewhere: regular files only, size-capped, paths confined to a folder.

Layer-neutral (like errors.py) because every layer that reads a file a user
or a session names needs it: ``io`` (session files, images), ``camera`` (the
folder-replay camera reads a session's captures.jsonl and images). A FIFO or
device is refused before anything blocks on it or reads it for ever, a final
symlink is not followed for a session's own files, and a path a session file
names stays inside the session folder.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path, PurePosixPath
from typing import BinaryIO

from lps_gui.errors import InputError

MAX_FILE_BYTES = 1 << 30  # 1 GB: no single file of lps is larger


def read_file_limited(path: Path | str, max_bytes: int = MAX_FILE_BYTES, what: str = "image",
                      follow_symlinks: bool = True) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (not a device, FIFO or folder)."""
    path = Path(path)
    f, st = open_regular(path, what, follow_symlinks)
    with f:
        if st.st_size > max_bytes:
            raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB, over the {max_bytes / 1e6:.0f} MB limit for an {what}")
        data = f.read(max_bytes + 1)
        if len(data) > max_bytes:  # grew while being read
            raise InputError(f"{path}: over the {max_bytes / 1e6:.0f} MB limit for an {what}")
        return data


def open_regular(path: Path | str, what: str = "file", follow_symlinks: bool = True, missing: str | None = None,
                 irregular: str | None = None) -> tuple[BinaryIO, os.stat_result]:
    """The open binary stream of a regular file and its stat; InputError (``missing`` / ``irregular``: the
    message after the path) for a missing file, a final link when not followed, a FIFO, device or folder.

    The open never blocks (O_NONBLOCK: a FIFO without a writer opens at once, then is refused by its stat).
    """
    path = Path(path)
    flags = os.O_RDONLY | (0 if follow_symlinks else getattr(os, "O_NOFOLLOW", 0)) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise InputError(f"{path}: {missing or f'{what} not found; check the path'}") from None
    except OSError as exc:
        if not follow_symlinks and path.is_symlink():
            raise InputError(f"{path}: is a symbolic link; session files must be regular files inside the session folder") from None
        raise InputError(f"{path}: cannot read the {what} ({exc.strerror})") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):  # before fdopen, which refuses a folder with its own error
        os.close(fd)
        raise InputError(f"{path}: {irregular or f'not a regular file (a {_kind(st.st_mode)}); give the {what} as a regular file'}")
    return os.fdopen(fd, "rb"), st


def _kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in ((stat.S_ISDIR, "folder"), (stat.S_ISFIFO, "FIFO"), (stat.S_ISCHR, "device"), (stat.S_ISBLK, "device"),
                       (stat.S_ISSOCK, "socket")):
        if test(mode):
            return name
    return "special file"


def check_regular_file(path: Path | str, what: str = "file", follow_symlinks: bool = True) -> os.stat_result:
    """The stat of ``path`` when it is a regular file; InputError before anything opens a FIFO or a device.

    For readers that take a path (cv2.FileStorage) and cannot be given the bytes.
    """
    path = Path(path)
    try:
        st = os.stat(path, follow_symlinks=follow_symlinks)
    except FileNotFoundError:
        raise InputError(f"{path}: {what} not found; check the path") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what} ({exc.strerror})") from None
    if stat.S_ISLNK(st.st_mode):
        raise InputError(f"{path}: is a symbolic link; session files must be regular files inside the session folder")
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{path}: not a regular file (a {_kind(st.st_mode)}); give the {what} as a regular file")
    return st


def check_relative(rel: str, where: str) -> str:
    """``rel`` if it is a plain relative path inside a session, else InputError naming ``where``."""
    plain = rel.replace("\\", "/")
    if plain and plain[0] != "/" and ".." not in plain and ":" not in plain:
        return rel  # nothing below can object (1600 captures: a few ms instead of tens)
    p = PurePosixPath(plain)
    if not rel or p.is_absolute() or Path(rel).is_absolute() or ".." in p.parts or (p.parts and p.parts[0].endswith(":")):
        raise InputError(f"{where}: file {rel!r} is outside the session folder; session files must be "
                         "relative paths inside it (e.g. images/000000.png)")
    return rel


def resolve_in_session(folder: Path | str, rel: str, where: str | None = None) -> Path:
    """The path of ``rel`` inside ``folder``, refused when it (or a symlinked folder on the way) leads outside."""
    folder = Path(folder)
    check_relative(rel, where or str(folder))
    full = folder / rel
    try:
        inside = full.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):  # a symlink loop
        inside = False
    if not inside:
        raise InputError(f"{where or full}: file {rel!r} resolves outside the session folder (through a symbolic "
                         "link); copy the files into the session")
    return full


