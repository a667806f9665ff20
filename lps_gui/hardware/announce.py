"""Ports announced by running emulators, so the GUI lists `lps emulate KIND`'s pty (as that kind) untyped.

A pseudo-terminal (/dev/pts/N) is not a serial port the system lists; the
emulator writes its path to a file named by its process id in a per-user
runtime folder and removes it when it stops. A reader skips (and removes)
files of processes that are gone.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable


def announce_dir() -> Path:
    """``$XDG_RUNTIME_DIR/lps-calib/ports``, else a per-user folder in the temp directory."""
    base = os.environ.get("XDG_RUNTIME_DIR") or os.path.join(tempfile.gettempdir(), f"lps-calib-{os.getuid()}")
    return Path(base) / "lps-calib" / "ports"


def announce(port: str, folder: Path | None = None, kind: str | None = None) -> Callable[[], None]:
    """Announce ``port`` (served as stage ``kind``, a registry name; None: a bare port, which the registry lists as
    its default port kind) for this process; returns the function that withdraws it."""
    folder = folder or announce_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        path = folder / str(os.getpid())
        path.write_text(f"{port}\n{kind}\n" if kind else f"{port}\n")
    except OSError:  # nowhere to write: the port can still be typed
        return lambda: None

    def withdraw() -> None:
        try:
            path.unlink()
        except OSError:
            pass

    return withdraw


def announced_ports(folder: Path | None = None) -> list[str]:
    """Ports announced by processes still running (sorted); stale announcements are removed."""
    return sorted({port for port, _kind in announced(folder)})


def announced(folder: Path | None = None) -> list[tuple[str, str]]:
    """(port, stage kind) announced by processes still running (sorted; the kind "" for a bare port, as an
    announcement without one); stale announcements are removed."""
    folder = folder or announce_dir()
    try:
        files = sorted(folder.iterdir())
    except OSError:
        return []
    out = []
    for f in files:
        try:
            pid = int(f.name)
            port, _, kind = f.read_text().strip().partition("\n")
        except (OSError, ValueError):
            continue
        if _alive(pid) and port and os.path.exists(port):
            out.append((port, kind.strip()))
        else:
            try:
                f.unlink()
            except OSError:
                pass
    return sorted(set(out))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True
