"""corners.vnl while a capture is still running: one block per view, appended and fsynced in capture order.

A live capture (:mod:`lps_gui.pipeline.live`) detects each frame as soon as
it is listed and appends its block: the view's image hash and stat comments
(:mod:`lps_gui.io.corners.hashes`), its detection method, the failure
reason of a view without a board, then its rows in the writer's number form.
Both readers take the file as it is (comments anywhere are the general
reader's), so ``lps detect`` keeps its current views and ``lps estimate``
reads it; when the plan completes the live capture rewrites it atomically in
the form ``lps detect`` writes.

A kill can tear only the last block: :func:`open_live_corners` reads the
complete blocks, whose views must follow captures.jsonl's order, and cuts the
file after the last one, so a resumed capture appends where the killed one
stopped. Any other corners.vnl (written by ``lps detect``, hand-made) is
replaced by a fresh live file: its views are detected again.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from lps_gui.errors import InputError
from lps_gui.io.atomic import fsync_dir, storage_error
from lps_gui.io.corners.hashes import PREFIX, STAT_PREFIX
from lps_gui.io.corners.vnl import HEADER, CornerTable, corners_vnl_bytes

LIVE_KEY = "live"
LIVE_NOTE = "capture in progress (blocks appended per view; rewritten as by lps detect when the capture completes)"
METHOD_PREFIX = "method "


@dataclass
class LiveView:
    """One view's block: what detection found, as ``pipeline.detect.ViewResult`` has it."""

    name: str
    corners_px: np.ndarray | None  # shape (N, 2), None when the board was not found
    method: str
    reason: str = ""
    sha256: str | None = None
    stat: str | None = None  # "size mtime_ns" of the image detected


def head_bytes(board_key: str) -> bytes:
    return f"{HEADER}\n## {LIVE_KEY} = {LIVE_NOTE}\n## board = {board_key}\n".encode("utf-8")


def block_bytes(view: LiveView, n_corners: int) -> bytes:
    """The view's comments and rows, the rows byte for byte as :func:`corners_vnl_bytes` writes them."""
    meta = {}
    if view.sha256:
        meta[PREFIX + view.name] = view.sha256
    if view.stat:
        meta[STAT_PREFIX + view.name] = view.stat
    meta[METHOD_PREFIX + view.name] = view.method
    corners = np.full((1, n_corners, 2), np.nan) if view.corners_px is None else np.asarray(view.corners_px, float)[None]
    failed = {view.name: view.reason or "board not found"} if view.corners_px is None else {}
    data = corners_vnl_bytes(CornerTable([view.name], corners, failed, meta))
    return data[len(HEADER) + 1 :]


class LiveCornersFile:
    """The open live corners.vnl: append one durable block per view."""

    def __init__(self, path: Path, fd: int, n_corners: int, views: list[LiveView]) -> None:
        self.path = path
        self._fd = fd
        self.n_corners = n_corners
        self.views = views  # complete blocks, in capture order

    def append(self, view: LiveView) -> None:
        """Write the view's block in one write and fsync it: after a kill it is there whole or cut off."""
        if " " in view.name:
            raise InputError("corners.vnl: file names with spaces cannot be stored; rename the images")
        data = block_bytes(view, self.n_corners)
        try:
            written = 0
            while written < len(data):
                written += os.write(self._fd, data[written:])
            os.fsync(self._fd)
        except OSError as exc:
            raise storage_error(self.path, exc) from exc
        self.views.append(view)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def open_live_corners(path: Path | str, board_key: str, n_corners: int, names: Sequence[str],
                      keep: int | None = None) -> LiveCornersFile:
    """Open (or start) the live corners file of a session whose captures.jsonl lists ``names`` in order.

    Complete blocks of a live file for this board whose views are the first of
    ``names`` are kept, at most ``keep`` of them (a resumed detection restarts
    its tracker where ``lps detect`` would); the file is cut after them.
    """
    path = Path(path)
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        if path.is_symlink():
            raise InputError(f"{path}: is a symbolic link; session files must be regular files inside the session folder") from None
        raise storage_error(path, exc) from exc
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise InputError(f"{path}: not a regular file; session files must be regular files")
        size = os.fstat(fd).st_size
        data = os.pread(fd, size, 0) if size else b""
        head = head_bytes(board_key)
        views, end = (_complete_blocks(data, len(head), n_corners, names) if data.startswith(head) else ([], 0))
        if keep is not None and len(views) > keep:
            end = views[keep - 1][1] if keep else len(head)
            views = views[:keep]
        if not views:
            os.ftruncate(fd, 0)
            os.pwrite(fd, head, 0)
            end = len(head)
        else:
            end = views[-1][1]
        os.ftruncate(fd, end)
        os.lseek(fd, end, os.SEEK_SET)
        os.fsync(fd)
        fsync_dir(path.parent)
    except OSError as exc:
        os.close(fd)
        raise storage_error(path, exc) from exc
    except BaseException:
        os.close(fd)
        raise
    return LiveCornersFile(path, fd, n_corners, [v for v, _ in views])


def _complete_blocks(data: bytes, start: int, n_corners: int, names: Sequence[str]) -> tuple[list[tuple[LiveView, int]], int]:
    """(view, end offset) of every complete block from ``start`` whose view is the next of ``names``."""
    out: list[tuple[LiveView, int]] = []
    pos = start
    while len(out) < len(names):
        name = names[len(out)]
        comments: dict[str, str] = {}
        failed = None
        while data.startswith(b"## ", pos):
            nl = data.find(b"\n", pos)
            if nl < 0:
                return out, pos
            body = data[pos + 3 : nl].decode("utf-8", "replace")
            if body.startswith("failed "):
                failed = body[7:].partition(":")[2].strip()
            else:
                key, _, value = body.partition(" = ")
                comments[key] = value
            pos = nl + 1
        if comments.get(METHOD_PREFIX + name) is None:
            return out, pos
        rows = 1 if failed is not None else n_corners
        row_end = pos
        for _ in range(rows):
            nl = data.find(b"\n", row_end)
            if nl < 0:
                return out, pos
            row_end = nl + 1
        lines = data[pos:row_end].split(b"\n")[:-1]
        if any(not line.startswith(name.encode("utf-8") + b" ") for line in lines):
            return out, pos
        corners = None
        if failed is None:
            try:
                corners = np.array([[np.nan if v == b"-" else float(v) for v in line.split()[1:3]] for line in lines])
            except ValueError:
                return out, pos
        out.append((LiveView(name, corners, comments[METHOD_PREFIX + name], failed or "",
                             comments.get(PREFIX + name), comments.get(STAT_PREFIX + name)), row_end))
        pos = row_end
    return out, pos
