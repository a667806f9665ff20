"""Reading JSON files with errors that name the file."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic


def read_json(path: Path | str, what: str = "file") -> Any:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (binary content); fix or regenerate the {what}") from None
    except FileNotFoundError:
        raise InputError(f"{path}: {what} not found; check the path") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what} ({exc.strerror})") from exc
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not valid JSON (line {exc.lineno}: {exc.msg}); fix or regenerate the {what}") from exc
    except RecursionError:
        raise InputError(f"{path}: JSON nested too deeply; fix or regenerate the {what}") from None


def json_bytes(data: Any) -> bytes:
    """The file content :func:`write_json` writes (indented, numpy-aware)."""
    return (json.dumps(data, indent=2, sort_keys=False, default=_default) + "\n").encode("utf-8")


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
