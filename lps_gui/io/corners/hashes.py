"""Which image each row of corners.vnl was detected in: its sha256, kept beside the corners.

corners.vnl carries one ``## sha256 <file> = <hex>`` comment per view (the
hash captures.jsonl lists for that file at detection time). When an image
is replaced, captures.jsonl lists a new hash; the old corners then no longer
belong to it: ``lps detect`` detects that view again and ``lps estimate``
refuses the stale rows instead of measuring the old image.

An image replaced on disk while captures.jsonl stays the same is caught
too: each view also keeps a ``## stat <file> = <size> <mtime_ns>`` comment
of the file its corners came from; when the file's size or mtime differ
(or no stat was kept) the file is hashed and compared with the view's
recorded sha256 (:func:`image_unchanged`).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable, Protocol

from lps_gui.errors import InputError
from lps_gui.io.atomic import sha256_file
from lps_gui.io.corners.vnl import CornerTable

PREFIX = "sha256 "
STAT_PREFIX = "stat "


class _Record(Protocol):
    file: str
    sha256: str | None


def image_hashes(records: Iterable[_Record]) -> dict[str, str | None]:
    return {r.file: r.sha256 for r in records}


def hash_meta(records: Iterable[_Record]) -> dict[str, str]:
    """corners.vnl metadata naming the image hash each view is detected in."""
    return {PREFIX + r.file: r.sha256 for r in records if r.sha256}


def corners_current(table: CornerTable, name: str, current: dict[str, str | None]) -> bool:
    """True when ``name``'s corners were detected in the image captures.jsonl lists now.

    A view without a recorded hash (a corners.vnl from before hashes were
    kept, or a capture without sha256) counts as current only when
    captures.jsonl lists no hash for it either.
    """
    return table.meta.get(PREFIX + name) == current.get(name)


def stale_views(table: CornerTable, current: dict[str, str | None]) -> list[str]:
    """Views in ``current`` whose corners ``table`` says came from another image (unrecorded hashes pass)."""
    rows = set(table.names)
    return [name for name in current
            if name in rows and PREFIX + name in table.meta and table.meta[PREFIX + name] != current.get(name)]


def _stat_text(path: Path) -> str | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return f"{st.st_size} {st.st_mtime_ns}"


def stat_meta(folder: Path, names: Iterable[str]) -> dict[str, str]:
    """corners.vnl metadata: size and mtime of each image file that exists (for :func:`image_unchanged`)."""
    out = {}
    for name in names:
        text = _stat_text(Path(folder) / name)
        if text is not None:
            out[STAT_PREFIX + name] = text
    return out


def image_unchanged(table: CornerTable, name: str, folder: Path) -> bool:
    """True unless ``name``'s image file differs from the one its corners in ``table`` came from.

    Same size and mtime as recorded: unchanged. Otherwise the file is hashed
    and compared with the recorded sha256; a view without a recorded hash
    counts as changed when its stat differs. A missing file counts as
    unchanged: there is nothing to detect again, and its corners are kept.
    """
    path = Path(folder) / name
    now = _stat_text(path)
    if now is None:
        return True
    recorded = table.meta.get(STAT_PREFIX + name)
    if recorded == now:
        return True
    want = table.meta.get(PREFIX + name)
    if want is None:
        return recorded is None  # neither stat nor hash kept: nothing to compare with
    try:
        return sha256_file(path) == want
    except (OSError, InputError):  # a link or a FIFO now: detected again, where the reader refuses it in one line
        return False
