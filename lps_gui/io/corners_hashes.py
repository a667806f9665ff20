"""Which image each row of corners.vnl was detected in: its sha256, kept beside the corners.

corners.vnl carries one ``## sha256 <file> = <hex>`` comment per view (the
hash captures.jsonl lists for that file at detection time). When an image
is replaced, captures.jsonl lists a new hash; the old corners then no longer
belong to it: ``lps detect`` detects that view again and ``lps estimate``
refuses the stale rows instead of measuring the old image.
"""
from __future__ import annotations

from typing import Iterable, Protocol

from lps_gui.io.corners_vnl import CornerTable

PREFIX = "sha256 "


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
