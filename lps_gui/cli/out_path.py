"""The one ``--out`` rule of every command.

An existing folder gets the command's usual file name inside it; otherwise
the suffix decides: a name with one of the command's suffixes is the file
to write (its folder must exist), a name without a suffix is a folder to
create. Any other suffix is refused with the suffixes the command writes.
Commands that write a set of files (demo) take folders only.
"""
from __future__ import annotations

from pathlib import Path

from lps_gui.errors import InputError


def resolve_out(out: str | Path | None, usual_name: str, default_folder: Path | str | None = None,
                suffixes: tuple[str, ...] = (), command: str = "lps") -> Path:
    """The file path a command writes for ``--out`` (``default_folder / usual_name`` without one).

    Folders named without a suffix are created; a named file's folder must exist.
    """
    if out is None or str(out) == "":
        folder = Path(default_folder) if default_folder is not None else Path.cwd()
        return folder / usual_name
    path = Path(out)
    if path.is_dir():
        return path / usual_name
    if path.exists() and not path.is_file():
        raise InputError(f"--out {path}: not a file or folder; choose another --out")
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
