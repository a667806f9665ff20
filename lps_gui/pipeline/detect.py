"""Detect the board in every image of a session (or a list of images), in parallel.

Images are split into contiguous chunks; each worker process tracks the
board through its chunk (:class:`ChessboardTracker`: one full detection,
then cheap predicted + refined corners), reading one image at a time, so
memory stays flat however long the session. Finished chunks stream back in
order of completion and drive the progress bar. A bad view (missing,
unreadable, truncated or changed image, wrong size, board not found) is
listed with its reason and the run goes on.

``detect_session`` writes ``corners.vnl`` atomically, keyed by the sha256 of
captures.jsonl: a re-run detects only the views not yet in it. A session with
targets (SPEC 13) gets one ArUco pass per image for all of them
(:func:`lps_gui.camera.charuco_targets.detect_targets`, partial targets kept)
and the SPEC 13 corners.vnl (:class:`CornerLayout`).
"""
from __future__ import annotations

import logging
import os
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from lps_gui.camera.processes import worker_pool
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.targets import Target, target_offsets
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import Cancelled, InputError
from lps_gui.io.atomic import sha256_file
from lps_gui.io.corners.hashes import corners_current, hash_meta, image_hashes, image_unchanged, stat_meta
from lps_gui.io.corners.target_vnl import TargetCornerTable, read_target_corners, write_target_corners
from lps_gui.io.corners.vnl import CornerTable, read_corners_vnl, write_corners_vnl
from lps_gui.io.session import Session

if TYPE_CHECKING:
    from lps_gui.camera.detection import ChessboardTracker

log = logging.getLogger(__name__)
Scene = Board | tuple[Target, ...]  # one board, or the targets of a row or constellation (SPEC 13)


@dataclass(frozen=True)
class ViewJob:
    """One image to detect: its name in the table, where it is, what it should hash to."""

    name: str
    path: str
    sha256: str | None = None
    session: str | None = None  # the session folder when ``path`` is a session file (checked to stay inside)


@dataclass
class ViewResult:
    name: str
    corners_px: np.ndarray | None  # shape (N, 2) float32, SPEC order
    method: str  # "track", "full", "failed"
    reason: str = ""


def load_grey(path: str, sha256: str | None = None, image_size: tuple[int, int] | None = None,
              session: str | None = None) -> tuple[np.ndarray | None, str]:
    """Decode an image file to 8-bit grey, or explain in one line why not.

    With ``session``, ``path`` is relative to it and must stay inside it
    (:mod:`lps_gui.io.session_paths`); every image's size is checked before
    it is read and its pixel count before it is decoded.
    """
    import hashlib

    from lps_gui.io.image_file import decode_image, read_file_limited
    from lps_gui.io.session_paths import read_session_file

    if not (Path(session or "") / path).exists() and not Path(session or "", path).is_symlink():
        return None, "image file missing"
    try:
        data = read_session_file(session, path) if session is not None else read_file_limited(path)
        if sha256 is not None and hashlib.sha256(data).hexdigest() != sha256:
            return None, "image changed since capture (sha256 differs from captures.jsonl)"
        image = decode_image(data, path)
    except InputError as exc:  # the caller names the view: drop the path the message starts with
        reason = str(exc)
        for prefix in (str(Path(session or "") / path), path):
            reason = reason.removeprefix(prefix + ": ")
        return None, reason
    if image is None:
        return None, "image unreadable or truncated"
    if image_size is not None and (image.shape[1], image.shape[0]) != tuple(image_size):
        return None, f"image is {image.shape[1]}x{image.shape[0]} but the camera is {image_size[0]}x{image_size[1]}"
    return image, ""


def _init_worker() -> None:
    import cv2

    cv2.setNumThreads(1)  # one process per core already


def detect_chunk(
    jobs: Sequence[ViewJob], board: Scene, image_size: tuple[int, int] | None = None, track: bool = True
) -> list[ViewResult]:
    """Track the board through ``jobs`` (capture order), or find every target of a tuple of them in each
    image; runs in a worker process."""
    from lps_gui.camera.detection import ChessboardTracker, DetectionOptions

    if isinstance(board, tuple):  # a row or constellation (SPEC 13)
        return [detect_targets_view(job, board, image_size) for job in jobs]
    tracker = ChessboardTracker(board, DetectionOptions(track=track))
    return [detect_view(tracker, job, image_size)[0] for job in jobs]


def detect_targets_view(job: ViewJob, targets: tuple[Target, ...], image_size: tuple[int, int] | None = None
                        ) -> ViewResult:
    """Every target of a row or constellation in one image: one ArUco pass, partial targets kept."""
    from lps_gui.camera.charuco_targets import detect_targets_dense

    image, reason = load_grey(job.path, job.sha256, image_size, job.session)
    if image is None:
        return ViewResult(job.name, None, "failed", reason)
    corners = detect_targets_dense(image, list(targets))
    if corners is None:
        return ViewResult(job.name, None, "failed", "no target found")
    return ViewResult(job.name, corners, "targets", "")


def detect_view(tracker: "ChessboardTracker", job: ViewJob, image_size: tuple[int, int] | None = None
                ) -> tuple[ViewResult, np.ndarray | None]:
    """One image of a sequence through ``tracker`` (the chunk's, or a live capture's): its result and the image."""
    from lps_gui.camera.charuco import detect_charuco

    board = tracker.board
    image, reason = load_grey(job.path, job.sha256, image_size, job.session)
    if image is None:
        tracker.reset()
        return ViewResult(job.name, None, "failed", reason), None
    if board.type == "charuco":
        corners, reason = detect_charuco(image, board)
        return ViewResult(job.name, corners, "charuco" if corners is not None else "failed", reason), image
    det = tracker.detect(image)
    corners = None if det.corners_px is None else det.corners_px.astype(np.float32)
    return ViewResult(job.name, corners, det.method, det.reason if corners is None else ""), image


def chunk_size(n_jobs: int, workers: int) -> int:
    """Frames per chunk: long enough to amortize a full detection, enough to balance cores.

    Every chunk starts with a full detection (~15 tracked frames' worth), so
    there are few: about two per process (the workers and this one, which
    takes chunks too), at most 64 frames each. A live capture's detection
    restarts its tracker at the same frames, so its corners are the bytes
    ``lps detect`` writes.
    """
    return int(np.clip(np.ceil(n_jobs / (2 * workers + 1)), 8, 64))


def default_workers(workers: int | None = None) -> int:
    return max(1, int(workers or os.cpu_count() or 1))


def _chunks(jobs: list[ViewJob], workers: int) -> list[list[ViewJob]]:
    size = chunk_size(len(jobs), workers)
    return [jobs[i : i + size] for i in range(0, len(jobs), size)]


def run_detection(
    jobs: list[ViewJob],
    board: Scene,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    workers: int | None = None,
    image_size: tuple[int, int] | None = None,
    track: bool = True,
) -> dict[str, ViewResult]:
    """Detect every job, in parallel when it pays; returns results by name.

    On cancel, raises :class:`Cancelled` carrying the finished results as
    ``exc.partial`` so the caller can keep them.
    """
    workers = default_workers(workers)
    chunks = _chunks(jobs, workers)
    total = len(jobs)
    results: dict[str, ViewResult] = {}
    counts = {"track": 0, "full": 0, "failed": 0, "charuco": 0, "targets": 0}

    def take(chunk_results: list[ViewResult]) -> None:
        for r in chunk_results:
            results[r.name] = r
            counts[r.method] = counts.get(r.method, 0) + 1
        msg = (f"tracked {counts['track']}, full {counts['full'] + counts['charuco'] + counts['targets']}, "
               f"failed {counts['failed']}")
        progress(len(results), total, msg)

    def check_cancel() -> None:
        if cancel is not None and cancel.cancelled:
            exc = Cancelled("detection cancelled; corners of the finished images are kept")
            exc.partial = results  # type: ignore[attr-defined]
            raise exc

    progress(0, total, "detecting")
    if workers == 1 or len(chunks) == 1:
        for chunk in chunks:
            check_cancel()
            take(detect_chunk(chunk, board, image_size, track))
        return results
    finished: set[int] = set()
    try:
        with worker_pool(min(workers, len(chunks)), _init_worker) as pool:  # workers end with this process
            # At most one queued chunk per worker (plus one spare); this process takes the next unqueued chunk whenever
            # it is free (the first while the workers start up), so no core waits while work is left.
            queue = list(range(1, len(chunks)))
            n_workers = min(workers, len(chunks))
            pending: dict[Future, int] = {}

            def refill() -> None:
                while queue and len(pending) < n_workers + 1:  # one spare, so a worker never waits for this process
                    i = queue.pop(0)
                    pending[pool.submit(detect_chunk, chunks[i], board, image_size, track)] = i

            refill()
            try:
                local = [0]
                while local or pending:
                    if local:
                        i = local.pop()
                        take(detect_chunk(chunks[i], board, image_size, track))
                        finished.add(i)
                    done, _ = wait(pending, timeout=0 if queue else 0.2, return_when=FIRST_COMPLETED)
                    for fut in done:
                        take(fut.result())
                        finished.add(pending.pop(fut))
                    refill()
                    if queue:
                        local.append(queue.pop(0))
                    check_cancel()
            except BaseException:
                for fut in pending:
                    fut.cancel()
                raise
    except BrokenProcessPool:  # e.g. a calling script without the __main__ guard
        log.warning("worker processes failed to start; detecting in this process")
        for i, chunk in enumerate(chunks):
            if i not in finished:
                check_cancel()
                take(detect_chunk(chunk, board, image_size, track))
    return results


@dataclass(frozen=True)
class CornerLayout:
    """What a session's corners.vnl holds: one board's corners (SPEC 7) or every target's (SPEC 13)."""

    scene: Scene
    n_corners: int
    key: str  # corners.vnl ``board`` meta: corners detected for another board or targets are not kept

    @property
    def targets(self) -> list[Target] | None:
        return list(self.scene) if isinstance(self.scene, tuple) else None

    def read(self, path: Path):
        return read_corners_vnl(path, self.n_corners) if self.targets is None else read_target_corners(path, self.targets)

    def table(self, names: list[str], corners: np.ndarray, failed: dict[str, str], meta: dict[str, str]):
        if self.targets is None:
            return CornerTable(names, corners, failed, meta)
        return TargetCornerTable(names, [t.id for t in self.targets], target_offsets(self.targets), corners, failed, meta)

    def write(self, path: Path, table) -> None:
        (write_corners_vnl if self.targets is None else write_target_corners)(path, table)


def corner_layout(session: Session) -> CornerLayout:
    """The session's board, or its targets laid end to end."""
    targets = session.targets()
    if targets is None:
        board = session.board()
        return CornerLayout(board, board.n_corners, board_key(board))
    key = "targets:" + ",".join(f"{t.id}/{board_key(t.board)}/{t.first_marker}" for t in targets)
    return CornerLayout(tuple(targets), int(target_offsets(targets)[-1]), key)


def _table(names: list[str], results: dict[str, ViewResult], n_corners: int, meta: dict[str, str],
           layout: CornerLayout | None = None):
    corners = np.full((len(names), n_corners, 2), np.nan)
    failed: dict[str, str] = {}
    for i, name in enumerate(names):
        r = results.get(name)
        if r is None:
            continue
        if r.corners_px is None:
            failed[name] = r.reason or "board not found"
        else:
            corners[i] = r.corners_px
    return CornerTable(names, corners, failed, meta) if layout is None else layout.table(names, corners, failed, meta)


def detect_images(
    paths: list[Path],
    board: Board,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    workers: int | None = None,
    track: bool = True,
) -> CornerTable:
    """Detect ``board`` in images given by path (in this order); names are the paths as given.

    ``track=False`` detects every image from scratch (unrelated views, e.g.
    an intrinsics set); tracking only pays in an LPS sequence.
    """
    if not paths:
        raise InputError("detect: no images given; pass image files or a session folder")
    jobs = [ViewJob(str(p), str(p)) for p in paths]
    results = run_detection(jobs, board, progress, cancel, workers, track=track)
    return _table([j.name for j in jobs], results, board.n_corners, {"board": board_key(board)})


def board_key(board: Board) -> str:
    """corners.vnl's ``board`` key of one board: corners detected for another board are not kept."""
    return f"{board.type}:{board.cols}x{board.rows}:{board.square_mm:g}"


def detect_session(
    session_dir: Path,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    workers: int | None = None,
    force: bool = False,
    track: bool = True,
) -> CornerTable:
    """Detect every capture of a session and write ``corners.vnl`` (atomically).

    If captures.jsonl is unchanged since the last run, every view is in
    corners.vnl and no image file changed since its corners were detected
    (size and mtime, else sha256: :func:`~lps_gui.io.corners.hashes.image_unchanged`),
    nothing is detected. Otherwise views with corners from their current image
    are kept and the others (new, replaced, or failed before) are detected;
    ``force`` redoes all. Rows use captures.jsonl's ``file`` names.
    Cancelling writes what was finished, then raises :class:`Cancelled`.
    """
    session = Session.open(session_dir)
    layout = corner_layout(session)
    board = layout.scene
    records = session.records()
    if not records:
        raise InputError(f"{session.captures_path}: no captures listed; capture or simulate images first")
    captures_sha = sha256_file(session.captures_path)
    names = [r.file for r in records]
    image_size = None  # checked against every image when the session knows its camera
    if session.has_intrinsics():
        try:
            image_size = session.intrinsics().image_size
        except InputError as exc:  # detection does not need intrinsics: go on without the size check
            log.warning("%s", exc)
    meta = session_corner_meta(session, records, captures_sha)
    kept: dict[str, ViewResult] = {}
    if not force and session.corners_path.exists():
        try:
            old = layout.read(session.corners_path)
        except InputError as exc:
            log.warning("ignoring unusable %s: %s", session.corners_path, exc)
        else:
            if old.meta.get("board", meta["board"]) == meta["board"]:
                current = image_hashes(records)
                replaced = []
                for name, corners in zip(old.names, old.corners_px):
                    if name not in old.failed and np.isfinite(corners).any() and corners_current(old, name, current):
                        if image_unchanged(old, name, session.folder):
                            kept[name] = ViewResult(name, corners, "kept")
                        else:
                            replaced.append(name)
                if replaced:
                    log.warning("detect: %d image(s) changed since their corners were detected, detecting them "
                                "again: %s", len(replaced), ", ".join(replaced[:5]) + (" ..." if len(replaced) > 5 else ""))
                if (old.meta.get("captures_sha256") == captures_sha and not replaced
                        and all(n in kept or n in old.failed for n in names)):
                    progress(len(names), len(names), "corners.vnl is up to date")
                    old.meta["up_to_date"] = "yes"  # for the caller; not written
                    return old
    jobs = [ViewJob(r.file, r.file, r.sha256, str(session.folder)) for r in records if r.file not in kept]
    meta.update(stat_meta(session.folder, names))  # before reading: a file replaced meanwhile fails its hash check
    results = dict(kept)
    try:
        if jobs:
            results.update(run_detection(jobs, board, progress, cancel, workers, image_size, track))
    except Cancelled as exc:
        results.update(getattr(exc, "partial", {}))
        table = _table(names, results, layout.n_corners, {**meta, "captures_sha256": "partial"}, layout)
        table.names = [n for n in names if n in results]
        table.corners_px = table.corners_px[[i for i, n in enumerate(names) if n in results]]
        write_session_corners(session, table, layout)
        raise
    table = session_corner_table(names, results, layout.n_corners, meta, layout)
    write_session_corners(session, table, layout)
    return table


def session_corner_meta(session: Session, records: Sequence[Any], captures_sha: str) -> dict[str, str]:
    """The head of a session's corners.vnl before the image stats: captures' hash, board or targets, image hashes."""
    return {"captures_sha256": captures_sha, "board": corner_layout(session).key, **hash_meta(records)}


def session_corner_table(names: list[str], results: dict[str, ViewResult], n_corners: int, meta: dict[str, str],
                         layout: CornerLayout | None = None) -> CornerTable:
    """The table ``lps detect`` writes: ``meta`` (with the image stats) and the count of each detection method."""
    methods = [r.method for r in results.values()]
    labels = {"track": "tracked", "full": "full", "charuco": "charuco", "targets": "targets", "kept": "kept",
              "failed": "failed"}
    tracked = layout is None or layout.targets is None  # a board is tracked from frame to frame; targets are found in every image
    meta = {**meta, "detection": ", ".join(f"{label} {methods.count(m)}" for m, label in labels.items()
                                           if m in methods or m == "track" and tracked)}
    return _table(names, results, n_corners, meta, layout)


def write_session_corners(session: Session, table: CornerTable, layout: CornerLayout | None = None) -> None:
    """corners.vnl under the session lock (a capture or another detection may be writing)."""
    from lps_gui.io.session_lock import SessionLock

    with SessionLock(session.folder):
        if layout is None:
            write_corners_vnl(session.corners_path, table)
        else:
            layout.write(session.corners_path, table)
