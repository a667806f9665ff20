"""Write several files that belong together (results.json, its CSVs, results/latest.json) as one set.

Every file goes to a checked temp file first. Only when all of them are
complete is a journal written (atomically) naming the renames; then the
renames run, and the journal is removed. A failure before the journal
leaves every old file as it was; a kill after it leaves a journal that the
next writer or reader of the folder rolls forward (:func:`recover_file_set`:
the temps are complete and fsynced, so the renames can always be finished).
A reader therefore sees the old set or the new one, never a mix, once any
lps command has looked at the folder. Names may lie one folder down
(``results/latest.json``) so the history record joins the same commit.
"""
from __future__ import annotations

import json
import os
import stat
from pathlib import Path, PurePosixPath
from typing import Mapping

from lps_gui.errors import InputError
from lps_gui.file_limits import read_file_limited
from lps_gui.io.atomic import TEMP_SUFFIX, _unlink, fsync_dir, storage_error, write_bytes_atomic, write_temp

JOURNAL = ".file-set-commit.json"


def _check_name(name: str) -> None:
    p = PurePosixPath(name)
    if not name or p.is_absolute() or any(part in ("", ".", "..") for part in p.parts) or len(p.parts) > 2:
        raise ValueError(f"write_file_set takes file names (at most one folder down), not {name!r}")


PROTECTED = ("session.json", "captures.jsonl", "corners.vnl", "truth.jsonl", ".lock", "board.json", "intrinsics.json")


def _check_temp_of(tmp: str, name: str) -> None:
    """ValueError unless ``tmp`` is a temp file :func:`write_temp` made for ``name`` and ``name`` is no session input.

    A journal only ever renames ``.NAME.PID-xxxx.tmp`` onto NAME in the same folder; one naming
    ``captures.jsonl -> session.json`` would destroy the session on a read-only command's recovery.
    """
    t, n = PurePosixPath(tmp), PurePosixPath(name)
    if t.parent != n.parent or ".." in t.parts or n.name in PROTECTED or n.parts[0] == "images":
        raise ValueError(tmp)
    if not (t.name.startswith(f".{n.name}.") and t.name.endswith(TEMP_SUFFIX)):
        raise ValueError(tmp)


def write_file_set(folder: Path | str, files: Mapping[str, bytes], last: str | None = None) -> dict[str, Path]:
    """Write ``files`` into ``folder`` all-or-nothing; ``last`` is renamed last (the index file).

    Returns the path of every file written.
    """
    folder = Path(folder)
    order = [n for n in files if n != last] + ([last] if last in files else [])
    for name in order:
        _check_name(name)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for name in order:
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise storage_error(folder, exc) from exc
    recover_file_set(folder)
    temps: dict[str, Path] = {}
    try:
        for name in order:
            temps[name] = write_temp(folder / name, files[name])
        journal = [[os.path.relpath(temps[name], folder), name] for name in order]  # temps are absolute
        write_bytes_atomic(folder / JOURNAL, json.dumps({"renames": journal}).encode("utf-8"))
    except BaseException:
        for tmp in temps.values():
            _unlink(tmp)
        raise
    _finish(folder, journal)
    return {name: folder / name for name in order}


def _finish(folder: Path, renames: list[list[str]]) -> None:
    """Run the journal's renames (those not done yet), sync the folders, drop the journal."""
    dirs = {folder}
    for tmp, name in renames:
        try:
            os.replace(folder / tmp, folder / name)
        except FileNotFoundError:
            pass  # done already (by a reader that rolled forward, or before a kill)
        except OSError as exc:
            raise storage_error(folder / name, exc) from exc
        dirs.add((folder / name).parent)
    for d in dirs:
        fsync_dir(d)
    _unlink(folder / JOURNAL)
    fsync_dir(folder)


def recover_file_set(folder: Path | str) -> bool:
    """Finish the commit a killed writer left in ``folder`` (its journal); True when there was one.

    Safe to call by anyone at any time: every rename is of a complete temp file and is done at most once.
    """
    folder = Path(folder)
    path = folder / JOURNAL
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISREG(st.st_mode):  # a FIFO or a link (to /dev/zero, /etc/passwd): never opened, never a journal
        _unlink(path)  # lps wrote; dropped like a torn one (a link's target is untouched), so the next commit can write its own
        return False
    try:
        data = read_file_limited(path, 1 << 20, "journal", follow_symlinks=False)
    except InputError:  # replaced meanwhile, or over 1 MB
        return False
    try:
        record = json.loads(data)
        renames = [[str(t), str(n)] for t, n in record["renames"]]
        for tmp, name in renames:
            _check_name(name)
            _check_temp_of(tmp, name)
    except (ValueError, KeyError, TypeError, RecursionError):  # a journal of another program, or torn: drop it
        _unlink(path)
        return False
    _finish(folder, renames)
    return True
