"""The one ``--out`` rule of every command.

An existing folder gets the command's usual file name inside it; otherwise
the suffix decides: a name with one of the command's suffixes is the file
to write (its folder must exist), a name without a suffix is a folder to
create. Any other suffix is refused with the suffixes the command writes.
Commands that write a set of files (demo) take folders only.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

from lps_gui.errors import InputError


def resolve_out(out: str | Path | None, usual_name: str, default_folder: Path | str | None = None,
                suffixes: tuple[str, ...] = (), command: str = "lps", *, own_session: Path | str | None = None,
                inputs: Iterable[Path | str] = ()) -> Path:
    """The file path a command writes for ``--out`` (``default_folder / usual_name`` without one).

    Folders named without a suffix are created; a named file's folder must exist. The path passes
    :func:`check_out_file` (``own_session``: the session the command works on; ``inputs``: what it reads).
    """
    guard = {"own_session": own_session, "inputs": inputs}
    if out is None or str(out) == "":
        folder = Path(default_folder) if default_folder is not None else Path.cwd()
        return folder / usual_name
    path = Path(out)
    if path.is_dir():
        return check_out_file(path / usual_name, allow=(usual_name,), **guard)
    check_out_file(path, allow=(usual_name,), **guard)
    suffix = path.suffix.lower()
    if suffix and suffix in suffixes:
        if not path.parent.is_dir():
            raise InputError(f"--out {path}: folder {path.parent} not found; create it or choose another --out")
        return path
    if not suffix and not path.exists():
        try:
            path.mkdir(parents=True)
        except OSError as exc:
            raise InputError(f"--out {path}: cannot create this folder ({exc.strerror}); choose another --out") from None
        return path / usual_name
    want = " or ".join(suffixes) if suffixes else "a folder"
    raise InputError(f"--out {path}: {command} writes {want}; give such a name or a folder (an existing folder "
                     f"gets {usual_name})")


OUT_HELP = "an existing folder gets {name} inside; a name ending in {suffixes} is the file; a name without suffix is a new folder"


def out_help(usual_name: str, suffixes: tuple[str, ...], default: str) -> str:
    """The --out help text of a command, stating the rule."""
    return f"where to write (default {default}): " + OUT_HELP.format(name=usual_name, suffixes="/".join(suffixes))


# what a session folder holds and no --out may replace (SPEC 7); the result set only by `lps estimate`
SESSION_INPUTS = ("session.json", "captures.jsonl", "corners.vnl", "truth.jsonl", ".lock", "board.json", "intrinsics.json")
SESSION_RESULTS = ("results.json", "positions.csv", "summary.csv")
SESSION_FOLDERS = ("images", "results")


def check_out_file(path: Path | str, allow: tuple[str, ...] = (), *, option: str = "--out",
                   own_session: Path | str | None = None, inputs: Iterable[Path | str] = ()) -> Path:
    """``path`` when it may be written as a file: a new name or an existing regular file that is nobody's data.

    The one guard of every file a command writes (``option`` names the option in the message). Refused:
    a symbolic link, anything that is not a regular file (a device node: a rename over /dev/null as root
    replaces the device; a FIFO blocks); any of the command's ``inputs`` (``--yaml board.json``); and in
    any session folder above it, however deep: its inputs, its images and its result history
    (``results/<run>/``), and its result set unless the session is ``own_session`` and the name is in
    ``allow`` (`lps estimate S` may replace S's results.json, `lps estimate B --out S` may not).
    """
    path = Path(path)
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise InputError(f"{option} {path}: exists and is not a regular file; give a new file name or a regular file")
    try:
        where = path.parent.resolve() / path.name
        own = Path(own_session).resolve() if own_session is not None else None
    except (OSError, RuntimeError):
        return path  # the writer names the problem with the folder
    for given in inputs:
        try:
            same = Path(given).resolve() == where or (path.exists() and Path(given).exists()
                                                        and os.path.samefile(given, path))
        except (OSError, RuntimeError, ValueError):
            same = False
        if same:
            raise InputError(f"{option} {path}: is one of this command's inputs; writing it would destroy it: "
                             "choose another name")
    for folder in where.parents:
        if not (folder / "session.json").is_file():
            continue
        rel = where.relative_to(folder).parts
        if len(rel) > 1:
            protected = rel[0] in SESSION_FOLDERS
        else:
            protected = rel[0] in SESSION_INPUTS or (rel[0] in SESSION_RESULTS + allow
                                                     and not (folder == own and rel[0] in allow))
        if protected:
            raise InputError(f"{option} {path}: is a file of the session {folder}; writing it would destroy the "
                             "session's data: choose a name outside the session's own files")
    return path


def check_out_folder(path: Path | str) -> Path:
    """``path`` created as a folder (or an existing one); InputError for a file, a link to one or an unwritable place."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"--out {path}: exists and is not a folder; give a folder (new or existing)")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--out {path}: cannot create this folder ({exc.strerror}); choose another --out") from None
    return path
