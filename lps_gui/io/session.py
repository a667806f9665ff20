"""A capture session folder (SPEC 7): session.json, captures.jsonl, images/.

Every image is written atomically before its line is appended and fsynced,
so a crash loses nothing already listed, and :meth:`Session.remaining_stops`
tells a resumed capture where to go on.
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.targets import Target
from lps_gui.core.planning.plan import Plan, PlannedStop
from lps_gui.errors import InputError, StorageError
from lps_gui.io.atomic import append_line_durable, sha256_bytes, write_bytes_atomic
from lps_gui.io.board_file import board_from_dict, board_to_dict
from lps_gui.io.intrinsics_file import intrinsics_from_dict, intrinsics_to_dict, read_intrinsics
from lps_gui.io.jsonfile import read_json, write_json
from lps_gui.io.session_paths import resolve_in_session
from lps_gui.io.targets_file import session_targets, targets_to_list

FORMAT = "lps-session/1"
SESSION_FILE = "session.json"
CAPTURES_FILE = "captures.jsonl"
CORNERS_FILE = "corners.vnl"
IMAGES_DIR = "images"


@dataclass(frozen=True)
class CaptureRecord:
    """One line of captures.jsonl."""

    index: int
    run: int
    direction: str  # "+" or "-"
    target_mm: float | tuple[float, float]  # [x, y] on a planar stage (SPEC 10)
    reported_mm: float | tuple[float, float] | None
    file: str  # relative to the session folder
    sha256: str | None
    time: float  # unix seconds
    frame: int = 0
    commanded_mm: float | None = None  # sent to the stage through a compensation table; absent without one
    settle_s: float | None = None  # settle detection: time until two frames agreed; absent without it
    since_move_s: float | None = None  # the frame's time after the stage reported its move done (capture clock)
    segment: int | None = None  # a stitched capture: which placement of the moved board; absent otherwise
    source: str | None = None  # "import": images the user already had (SPEC 16); absent for a capture

    def to_json(self) -> str:
        d = asdict(self)
        for key in ("target_mm", "reported_mm"):
            if isinstance(d[key], tuple):
                d[key] = list(d[key])
        for key in ("commanded_mm", "settle_s", "since_move_s", "segment", "source"):
            if d[key] is None:
                del d[key]
        return json.dumps(d, separators=(",", ":"))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "CaptureRecord":
        """A record from one parsed line; ValueError names the field that is wrong."""
        from lps_gui.io.capture_fields import capture_fields

        return cls(**capture_fields(d))


def _identity(folder: Path) -> tuple[int, int] | None:
    """(st_dev, st_ino) of a folder, or None when there is none at that path."""
    try:
        st = os.stat(folder)
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


OBJECT_KEYS = ("plan", "camera", "stage", "truth", "asme_test", "acquisition")


class Session:
    """A session folder on disk; cheap to open, reads files on demand."""

    def __init__(self, folder: Path | str, meta: dict[str, Any]):
        self.folder = Path(folder)
        self.meta = meta
        self._identity = _identity(self.folder)

    def check_present(self) -> None:
        """StorageError when the folder opened is no longer at its path (moved, removed, replaced).

        Checked before every write: a session moved mid-capture would otherwise be split, the old path
        recreated with the rest of the frames and a new session.json.
        """
        if self._identity is None or _identity(self.folder) != self._identity:
            raise StorageError(f"{self.folder}: the session folder was moved or removed while lps was writing to it; "
                               "nothing more is written: put it back (or resume the moved session with --resume)")

    # -------------------------------------------------------------- create/open
    @classmethod
    def create(
        cls,
        folder: Path | str,
        board: Board | list[Target],
        plan: Plan,
        intrinsics: CameraIntrinsics | str | None = None,
        camera: dict[str, Any] | None = None,
        stage: dict[str, Any] | None = None,
        truth: dict[str, Any] | None = None,
        extra: dict[str, Any] | None = None,
    ) -> "Session":
        """Write session.json into ``folder`` (created); refuse to overwrite a session.

        ``board`` is the one board, or the list of targets of a row or constellation (SPEC 13).
        """
        folder = Path(folder)
        if (folder.exists() or folder.is_symlink()) and not folder.is_dir():
            raise InputError(f"{folder}: exists and is not a folder; give a new or an empty folder for the session")
        if (folder / SESSION_FILE).exists() or (folder / SESSION_FILE).is_symlink():
            raise InputError(f"{folder}: already holds a session; use --resume or choose an empty folder")
        try:
            (folder / IMAGES_DIR).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"{folder}: cannot create the session folder ({exc.strerror}); choose another place") from None
        meta: dict[str, Any] = {
            "format": FORMAT,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            **({"board": board_to_dict(board)} if isinstance(board, Board) else {"targets": targets_to_list(board)}),
            "intrinsics": intrinsics_to_dict(intrinsics) if isinstance(intrinsics, CameraIntrinsics) else intrinsics,
            "camera": camera or {},
            "stage": stage or {},
            "plan": plan.to_dict(),
        }
        if extra:
            meta.update(extra)
        if truth is not None:
            meta["truth"] = truth
        write_json(folder / SESSION_FILE, meta)
        return cls(folder, meta)

    @classmethod
    def open(cls, folder: Path | str) -> "Session":
        folder = Path(folder)
        if not folder.is_dir():
            raise InputError(f"{folder}: session folder not found; check the path")
        meta = read_json(folder / SESSION_FILE, "session file", follow_symlinks=False)
        if not isinstance(meta, dict) or meta.get("format") != FORMAT:
            raise InputError(f"{folder / SESSION_FILE}: not an {FORMAT} session file")
        for key in OBJECT_KEYS:  # every reader takes these as objects: "truth": "x" must not reach them
            if meta.get(key) is not None and not isinstance(meta[key], dict):
                raise InputError(f"{folder / SESSION_FILE}: {key} is {type(meta[key]).__name__}, not an object; fix or "
                                 "regenerate session.json")
        return cls(folder, meta)

    def save_meta(self) -> None:
        self.check_present()
        write_json(self.folder / SESSION_FILE, self.meta)

    # -------------------------------------------------------------- contents
    def board(self) -> Board:
        if "targets" in self.meta and not self.meta.get("board"):
            raise InputError(f"{self.folder / SESSION_FILE}: names targets (a row or constellation, docs/targets.md), "
                             "not one board; this command does not take such sessions yet")
        return board_from_dict(self.meta.get("board") or {}, str(self.folder / SESSION_FILE))

    def targets(self) -> list[Target] | None:
        """The session's targets (SPEC 13), or None for a single-board session."""
        return session_targets(self.meta, str(self.folder / SESSION_FILE))

    @property
    def axes(self) -> list[str]:
        """The axes the camera moves along: ["X"] (a line) or ["X", "Y"] (a planar stage, SPEC 10)."""
        plan = self.meta.get("plan") or {}
        axes = plan.get("axes", ["X"]) if isinstance(plan, dict) else None
        if axes in (["X"], ["X", "Y"]) or axes is None and isinstance(plan, dict):
            return list(axes or ["X"])
        raise InputError(f"{self.folder / SESSION_FILE}: plan.axes is {axes!r}; a session measures [\"X\"] (a line) or "
                         "[\"X\", \"Y\"] (a planar stage): fix or regenerate session.json")

    @property
    def planar(self) -> bool:
        return len(self.axes) == 2

    def plan(self) -> Plan:
        d = self.meta.get("plan") or {}
        return Plan.from_dict(d)

    def has_intrinsics(self) -> bool:
        return bool(self.meta.get("intrinsics"))

    def intrinsics(self) -> CameraIntrinsics:
        """Embedded intrinsics, or read from a path relative to the session."""
        value = self.meta.get("intrinsics")
        if not value:
            raise InputError(
                f"{self.folder / SESSION_FILE}: has no intrinsics; pass --intrinsics FILE or run `lps intrinsics` first"
            )
        if isinstance(value, str):  # a file inside the session, never one elsewhere a copied session.json names
            where = f"{self.folder / SESSION_FILE}: intrinsics"
            return read_intrinsics(resolve_in_session(self.folder, value, where), follow_symlinks=False)
        return intrinsics_from_dict(value, str(self.folder / SESSION_FILE))

    @property
    def truth(self) -> dict[str, Any] | None:
        return self.meta.get("truth")

    @property
    def captures_path(self) -> Path:
        return self.folder / CAPTURES_FILE

    @property
    def corners_path(self) -> Path:
        return self.folder / CORNERS_FILE

    def records(self) -> list[CaptureRecord]:
        """Every complete line of captures.jsonl (a torn last line is ignored).

        A line that is not a record, a ``file`` outside the session folder or
        an index listed twice (two writers at once) is an error naming the line.
        """
        from lps_gui.io.capture_fields import parse_capture_lines

        path = self.captures_path
        if not path.exists() and not path.is_symlink():
            return []
        records = [CaptureRecord(**fields) for fields in parse_capture_lines(path)]
        planar = self.planar
        for r in records:
            if isinstance(r.target_mm, tuple) != planar:
                raise InputError(f"{path}: capture {r.index} has target_mm {r.target_mm!r}; this session measures "
                                 f"{'X,Y: give [x, y]' if planar else 'one axis: give one number'} (mm)")
        return records

    def append(self, record: CaptureRecord) -> None:
        self.check_present()
        append_line_durable(self.captures_path, record.to_json())

    def write_image(self, name: str, data: bytes) -> tuple[str, str]:
        """Store encoded image bytes atomically; returns (relative file, sha256)."""
        rel = f"{IMAGES_DIR}/{name}"
        self.check_present()
        write_bytes_atomic(self.folder / rel, data)
        return rel, sha256_bytes(data)

    def remaining_stops(self) -> list[PlannedStop]:
        """Planned frames not yet listed in captures.jsonl, in capture order."""
        done = {r.index for r in self.records()}
        return [s for s in self.plan().stops() if s.index not in done]
