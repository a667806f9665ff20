"""Reading JSON files with errors that name the file."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.image_file import read_file_limited

MAX_JSON_BYTES = 256 << 20  # a results.json of 100000 views is ~100 MB


def read_json(path: Path | str, what: str = "file", follow_symlinks: bool = True) -> Any:
    """Parsed JSON of a regular file (a FIFO or device is refused before it is opened for reading, the size capped).

    ``follow_symlinks=False`` for the files of a session folder: lps never writes them as links.
    """
    path = Path(path)
    try:
        text = read_file_limited(path, MAX_JSON_BYTES, what, follow_symlinks=follow_symlinks).decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (binary content); fix or regenerate the {what}") from None
    return parse_json(text, str(path), what)


class _DuplicateKey(ValueError):
    """An object names a key twice (args: the key)."""


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out = dict(pairs)
    if len(out) != len(pairs):
        seen: set[str] = set()
        raise _DuplicateKey(next(k for k, _ in pairs if k in seen or seen.add(k)))  # type: ignore[func-returns-value]
    return out


def parse_json(text: str, where: str, what: str = "file") -> Any:
    """JSON text parsed, every failure one InputError naming ``where``: the parser's own errors caught here, at the boundary.

    Besides syntax: an object naming a key twice (``"square_mm"`` twice: json keeps the last silently, a
    different board), an integer over Python's 4300-digit limit (a ValueError, not a JSONDecodeError) and
    nesting too deep for the parser.
    """
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as exc:
        raise InputError(f"{where}: not valid JSON (line {exc.lineno}: {exc.msg}); fix or regenerate the {what}") from None
    except _DuplicateKey as exc:
        raise InputError(f"{where}: key {exc.args[0]!r} appears twice in one object (which one counts is a guess); "
                         f"keep one and fix or regenerate the {what}") from None
    except ValueError as exc:  # "Exceeds the limit (4300 digits) for integer string conversion"
        raise InputError(f"{where}: a number in it is out of range ({str(exc).split(';')[0]}); fix or regenerate "
                         f"the {what}") from None
    except RecursionError:
        raise InputError(f"{where}: JSON nested too deeply; fix or regenerate the {what}") from None


def json_bytes(data: Any) -> bytes:
    """The file content :func:`write_json` writes: objects indented, each list item on one line (numpy-aware).

    An object is laid out like ``json.dumps(indent=2)``; a list of numbers or
    strings stays on one line and a list of rows (objects, lists) gets one row
    per line, each row compact. The text still reads and diffs well (a
    results.json position is one line), and every row goes through the C
    encoder: ``indent=`` falls back to the pure-Python encoder, slow for the
    hundreds of thousands of items of a large results.json. The values are the same (same
    float repr); ``json.loads`` gives back what ``indent=2`` would.
    """
    parts: list[str] = []
    _layout(data, 0, parts)
    parts.append("\n")
    return "".join(parts).encode("utf-8")


_SCALARS = (str, int, float, bool, type(None))
_NESTED = (dict, list, tuple)


def _compact(obj: Any) -> str:
    """One JSON value on one line, by the C encoder."""
    return _ENCODER.encode(obj)


def _key(key: Any) -> str:
    """A non-string object key, encoded as json writes it (1 -> '"1"', True -> '"true"')."""
    return _compact({key: 0})[1:-4]


def _layout(obj: Any, level: int, parts: list[str]) -> None:
    """Append the text of ``obj`` at nesting ``level`` to ``parts`` (the layout of :func:`json_bytes`)."""
    if isinstance(obj, dict) and obj:
        inner = "\n" + "  " * (level + 1)
        sep = "{" + inner
        for key, value in obj.items():
            parts.append(sep + (_compact(key) if isinstance(key, str) else _key(key)) + ": ")
            _layout(value, level + 1, parts)
            sep = "," + inner
        parts.append("\n" + "  " * level + "}")
    elif isinstance(obj, (list, tuple)) and any(isinstance(v, _NESTED) or getattr(v, "ndim", 0) for v in obj):
        inner = "\n" + "  " * (level + 1)
        parts.append("[" + inner + ("," + inner).join(_compact(v) for v in obj) + "\n" + "  " * level + "]")
    elif isinstance(obj, (_SCALARS, dict, list, tuple)):
        parts.append(_compact(obj))
    else:  # numpy arrays and scalars, paths: what json's default hook makes of them, laid out the same way
        _layout(_default(obj), level, parts)


def write_json(path: Path | str, data: Any) -> None:
    write_bytes_atomic(path, json_bytes(data))


def _default(obj: Any) -> Any:
    import numpy as np

    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serializable: {type(obj).__name__}")


_ENCODER = json.JSONEncoder(separators=(", ", ": "), default=_default)  # indent=None: the C encoder
