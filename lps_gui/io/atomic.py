"""Crash-safe file writes: a file is either the old one or the complete new one.

Write to a temporary name in the same folder, fsync, check the temp file
holds every byte, rename over the target, fsync the folder. A write that
fails (disk full, read-only folder) raises :class:`StorageError` and leaves
the old file in place; nothing is renamed unless it was checked.
Appends to a log are fsynced line by line so a crash loses at most the line
being written, which readers then ignore.
"""
from __future__ import annotations

import errno
import hashlib
import os
import re
import tempfile
from pathlib import Path

from lps_gui.errors import InputError, StorageError
from lps_gui.file_limits import MAX_FILE_BYTES, open_regular


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def storage_error(path: Path | str, exc: OSError) -> StorageError:
    """The one-line error of a failed write, naming the file and what to do."""
    reason = exc.strerror or str(exc)
    if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO):
        hint = "free disk space"
    elif exc.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        hint = "make the folder writable or choose another"
    else:
        hint = "check the disk and the folder"
    return StorageError(f"{path}: cannot write ({reason}); {hint} and run again (the previous file is kept)")


TEMP_SUFFIX = ".tmp"
_TEMP_NAME = re.compile(r"^\..+\.(\d+)-[^.]*\.tmp$")  # .NAME.PID-RANDOM.tmp


def _temp_prefix(path: Path) -> str:
    """``.NAME.PID-``: the writer's pid in the name tells a killed run's temp file from a live one."""
    return f".{path.name}.{os.getpid()}-"


def remove_orphan_temps(folder: Path | str) -> list[Path]:
    """Delete the temp files in ``folder`` whose writing process is gone (killed mid-write); returns them.

    Only temp files named by :func:`write_temp` are touched, and only when their pid no longer runs:
    a live writer's temp file (another command writing a report into the session) is left alone.
    """
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        m = _TEMP_NAME.match(entry.name)
        if not m or not entry.is_file(follow_symlinks=False):
            continue
        pid = int(m.group(1))
        try:
            os.kill(pid, 0)
            continue  # that process still runs
        except ProcessLookupError:
            pass
        except (PermissionError, OverflowError, ValueError):
            continue
        _unlink(entry.path)
        removed.append(Path(entry.path))
    return removed


def temp_path(path: Path) -> Path:
    """A fresh temporary name beside ``path`` (same folder, so the rename is atomic).

    Its mode follows the user's umask (mkstemp makes 0600): a writer that fills
    it (QPdfWriter keeps the mode of the file it opens) leaves a file that reads
    like any other output.
    """
    try:
        fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=TEMP_SUFFIX, dir=path.parent)
    except OSError as exc:
        raise storage_error(path, exc) from exc
    try:
        os.fchmod(fd, 0o666 & ~_umask())
    finally:
        os.close(fd)
    return Path(tmp)


def write_temp(path: Path, data: bytes) -> Path:
    """Write ``data`` to a new temp file beside ``path``, fsynced and size-checked; returns its path."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=TEMP_SUFFIX, dir=path.parent)
    except OSError as exc:
        raise storage_error(path, exc) from exc
    try:
        os.fchmod(fd, 0o666 & ~_umask())  # mkstemp makes 0600; files should read like any other
        view = memoryview(data)
        while view:
            n = os.write(fd, view)
            if n <= 0:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            view = view[n:]
        os.fsync(fd)
        size = os.fstat(fd).st_size
        if size != len(data):
            raise OSError(errno.EIO, f"wrote {size} of {len(data)} bytes")
    except OSError as exc:
        os.close(fd)
        _unlink(tmp)
        raise storage_error(path, exc) from exc
    except BaseException:
        os.close(fd)
        _unlink(tmp)
        raise
    os.close(fd)
    return Path(tmp)


def commit_temp(tmp: Path | str, path: Path | str, expected_size: int | None = None, min_size: int = 1,
                ends_with: bytes = b"") -> None:
    """Check a finished temp file (fsync, size) and rename it over ``path``.

    For writers that fill the temp file themselves (a QPdfWriter): the file
    must exist, hold at least ``min_size`` bytes (exactly ``expected_size`` if
    given), end with ``ends_with`` (a format's trailer: Qt reports no error
    when a full disk cuts a PDF short) and fsync cleanly, or it is deleted and :class:`StorageError`
    raised with the old ``path`` untouched.
    """
    tmp, path = Path(tmp), Path(path)
    try:
        fd = os.open(tmp, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        try:
            os.fsync(fd)
            size = os.fstat(fd).st_size
            tail = os.pread(fd, len(ends_with) + 64, max(0, size - len(ends_with) - 64)) if ends_with else b""
        finally:
            os.close(fd)
        if size < min_size or (expected_size is not None and size != expected_size):
            want = expected_size if expected_size is not None else f">= {min_size}"
            raise OSError(errno.EIO, f"incomplete file ({size} bytes, expected {want})")
        if ends_with and not tail.rstrip().endswith(ends_with):
            raise OSError(errno.EIO, f"incomplete file ({size} bytes, no {ends_with.decode(errors='replace')} trailer)")
        os.replace(tmp, path)
    except OSError as exc:
        _unlink(tmp)
        raise storage_error(path, exc) from exc
    fsync_dir(path.parent)


def _unlink(path: Path | str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def write_bytes_atomic(path: Path | str, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file, fsync, size check, rename)."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise storage_error(path, exc) from exc
    if path.is_symlink():
        raise InputError(f"{path}: is a symbolic link; refusing to replace it (use a regular file)")
    tmp = write_temp(path, data)
    commit_temp(tmp, path, expected_size=len(data), min_size=0)


def write_text_atomic(path: Path | str, text: str) -> None:
    write_bytes_atomic(path, text.encode("utf-8"))


def append_line_durable(path: Path | str, line: str) -> None:
    """Append one line (newline added) and fsync; repair a torn last line first.

    A symlinked log is refused (O_NOFOLLOW): the repair truncates, and must
    never truncate a file elsewhere.
    """
    path = Path(path)
    if "\n" in line:
        raise ValueError("append_line_durable takes a single line")
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise InputError(f"{path}: is a symbolic link; session files must be regular files in the session folder") from None
        raise storage_error(path, exc) from exc
    with os.fdopen(fd, "r+b") as f:
        import stat

        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise InputError(f"{path}: not a regular file; session files must be regular files")
        try:
            size = f.seek(0, os.SEEK_END)
            if size:
                f.seek(size - 1)
                if f.read(1) != b"\n":  # a crash tore the last line: drop it
                    f.seek(0)
                    content = f.read()
                    keep = content[: content.rfind(b"\n") + 1]
                    f.truncate(len(keep))
            end = f.seek(0, os.SEEK_END)
            f.write(line.encode("utf-8") + b"\n")
            f.flush()
            os.fsync(f.fileno())
        except OSError as exc:
            try:  # a partial line must not stay behind (the next reader would call it torn)
                f.truncate(end)
            except (OSError, UnboundLocalError):
                pass
            raise storage_error(path, exc) from exc


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: Path | str, chunk: int = 1 << 20, max_bytes: int = MAX_FILE_BYTES) -> str:
    """The sha256 of a regular file, opened without following a final link and without blocking.

    A session's image replaced by a FIFO, or by a link to /dev/urandom or to a FIFO elsewhere, is
    refused (InputError) instead of being read for ever.
    """
    h = hashlib.sha256()
    f, st = open_regular(path, "file", follow_symlinks=False)
    with f:
        if st.st_size > max_bytes:
            raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB, over the {max_bytes / 1e6:.0f} MB limit of a file lps hashes")
        left = max_bytes + 1
        while left > 0 and (block := f.read(min(chunk, left))):
            h.update(block)
            left -= len(block)
    return h.hexdigest()


def check_writable(folder: Path | str, need_bytes: int = 0) -> None:
    """Raise InputError before any work if ``folder`` cannot take ``need_bytes``."""
    import shutil

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".write-probe"
        probe.write_bytes(b"x")
        probe.unlink()
    except OSError as exc:
        raise InputError(f"{folder}: cannot write here ({exc.strerror}); choose another folder") from exc
    free = shutil.disk_usage(folder).free
    if need_bytes and free < need_bytes:
        raise InputError(
            f"{folder}: {free / 1e6:.0f} MB free but the session needs about {need_bytes / 1e6:.0f} MB; free space or choose another disk"
        )
