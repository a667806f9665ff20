"""Crash-safe file writes: a file is either the old one or the complete new one.

Write to a temporary name in the same folder, fsync, rename over the target,
fsync the folder. Appends to a log are fsynced line by line so a crash loses
at most the line being written, which readers then ignore.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path


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


def write_bytes_atomic(path: Path | str, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file, fsync, rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_umask())  # mkstemp makes 0600; files should read like any other
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    fsync_dir(path.parent)


def write_text_atomic(path: Path | str, text: str) -> None:
    write_bytes_atomic(path, text.encode("utf-8"))


def append_line_durable(path: Path | str, line: str) -> None:
    """Append one line (newline added) and fsync; repair a torn last line first."""
    path = Path(path)
    if "\n" in line:
        raise ValueError("append_line_durable takes a single line")
    with open(path, "a+b") as f:
        size = f.seek(0, os.SEEK_END)
        if size:
            f.seek(size - 1)
            if f.read(1) != b"\n":  # a crash tore the last line: drop it
                f.seek(0)
                content = f.read()
                keep = content[: content.rfind(b"\n") + 1]
                f.truncate(len(keep))
        f.seek(0, os.SEEK_END)
        f.write(line.encode("utf-8") + b"\n")
        f.flush()
        os.fsync(f.fileno())


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: Path | str, chunk: int = 1 << 20) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


def check_writable(folder: Path | str, need_bytes: int = 0) -> None:
    """Raise InputError before any work if ``folder`` cannot take ``need_bytes``."""
    import shutil

    from lps_gui.errors import InputError

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
