"""Write several files that belong together (results.json and its CSVs) as one set.

Every file goes to a checked temp file first; only when all of them are
complete are they renamed, one after the other, in a row of renames that
cannot run out of disk space. A failure before the renames leaves every old
file as it was. The set is given as a folder and ``{name: bytes}`` so a
caller can aim it at a fresh folder (a results history entry) as easily as
at the session folder.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

from lps_gui.io.atomic import _unlink, commit_temp, fsync_dir, storage_error, write_temp


def write_file_set(folder: Path | str, files: Mapping[str, bytes], last: str | None = None) -> dict[str, Path]:
    """Write ``files`` into ``folder`` all-or-nothing; ``last`` is renamed last (the index file).

    Returns the path of every file written.
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise storage_error(folder, exc) from exc
    order = [n for n in files if n != last] + ([last] if last in files else [])
    temps: dict[str, Path] = {}
    try:
        for name in order:
            if "/" in name or name in ("", ".", ".."):
                raise ValueError(f"write_file_set takes plain file names, not {name!r}")
            temps[name] = write_temp(folder / name, files[name])
    except BaseException:
        for tmp in temps.values():
            _unlink(tmp)
        raise
    for i, name in enumerate(order):
        try:
            commit_temp(temps[name], folder / name, expected_size=len(files[name]), min_size=0)
        except BaseException:
            for later in order[i + 1:]:
                _unlink(temps[later])
            raise
    fsync_dir(folder)
    return {name: folder / name for name in order}


