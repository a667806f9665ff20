"""Targets of a row or constellation (SPEC 13): ChArUco boards with disjoint marker ids.

One board covers about the camera's field of view; the whole travel of a long
axis is measured against several boards fixed along it with unknown mounting
poses. Each target is a :class:`Board` of type ``charuco`` plus an id and the
first marker id it uses, so one ArUco pass over an image tells every target's
markers apart. Geometry only: reading the session's list lives in ``io``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError


def markers_of(board: Board) -> int:
    """Number of ArUco markers on a ChArUco board: half its (cols+1) x (rows+1) squares, rounded down."""
    return (board.cols + 1) * (board.rows + 1) // 2


@dataclass(frozen=True)
class Target:
    """One mounted board: ``board`` (type charuco), its ``id`` and its marker id range.

    Corner (r, c) of the target is at (c s, r s, 0) in its own frame and has
    corner number r * cols + c (SPEC 13), exactly as on a single board.
    """

    id: str
    board: Board
    first_marker: int = 0
    square_mm_uncertainty_um: float | None = None
    scale_ppm: float | None = None

    def __post_init__(self) -> None:
        if not self.id or any(ch.isspace() for ch in self.id):
            raise InputError(f"targets: id {self.id!r} must be a non-empty name without spaces (e.g. T0)")
        if self.board.type != "charuco":
            raise InputError(f"targets: target {self.id} is a {self.board.type}; targets must be charuco boards "
                             "(their markers tell the targets apart)")
        marker = self.board.marker_mm
        if marker is not None and not 0 < marker < self.board.square_mm:
            raise InputError(f"targets: target {self.id} marker_mm {marker} must be smaller than its square_mm "
                             f"{self.board.square_mm} (and positive)")
        if self.first_marker < 0:
            raise InputError(f"targets: target {self.id} first_marker {self.first_marker} must be 0 or more")

    @property
    def n_markers(self) -> int:
        return markers_of(self.board)

    @property
    def marker_range(self) -> range:
        """Marker ids this target uses: first_marker ... first_marker + n_markers - 1."""
        return range(self.first_marker, self.first_marker + self.n_markers)

    @property
    def marker_ids(self) -> np.ndarray:
        return np.arange(self.first_marker, self.first_marker + self.n_markers, dtype=np.int32)


def check_targets(targets: list[Target], dictionary_size: dict[str, int] | None = None) -> None:
    """Raise InputError unless ids are unique and marker ranges are disjoint (within one dictionary).

    ``dictionary_size`` maps a dictionary name to its number of markers, so a
    range past the dictionary's end is caught here rather than by OpenCV.
    """
    if not targets:
        raise InputError("targets: the list is empty; name at least one target or use a single board")
    seen: dict[str, Target] = {}
    for t in targets:
        if t.id in seen:
            raise InputError(f"targets: id {t.id} is used twice; give every target its own id")
        seen[t.id] = t
    by_dict: dict[str, list[Target]] = {}
    for t in targets:
        by_dict.setdefault(t.board.dictionary or "", []).append(t)
    for name, group in by_dict.items():
        group = sorted(group, key=lambda t: t.first_marker)
        for a, b in zip(group, group[1:]):
            if b.first_marker < a.marker_range.stop:
                raise InputError(
                    f"targets: {a.id} uses markers {a.marker_range.start}-{a.marker_range.stop - 1} and {b.id} "
                    f"starts at {b.first_marker}; set {b.id}'s first_marker to {a.marker_range.stop} or more")
        size = (dictionary_size or {}).get(name)
        if size is not None and group[-1].marker_range.stop > size:
            last = group[-1]
            raise InputError(f"targets: {last.id} needs markers up to {last.marker_range.stop - 1} but "
                             f"{name or 'the dictionary'} has {size}; use a larger dictionary or fewer markers")


def target_offsets(targets: list[Target]) -> np.ndarray:
    """Start of each target's corners when all targets' corners are laid end to end, and the total (T + 1,)."""
    return np.concatenate([[0], np.cumsum([t.board.n_corners for t in targets])]).astype(int)


def pack_targets(boards: list[Board], ids: list[str] | None = None) -> list[Target]:
    """Targets for ``boards`` with consecutive marker ranges (what ``lps make-targets`` prints)."""
    out: list[Target] = []
    first = 0
    for j, board in enumerate(boards):
        out.append(Target(ids[j] if ids else f"T{j}", board, first))
        first += markers_of(board)
    return out
