"""Results while the stage still moves: detection, a running estimate and checks beside a capture.

:class:`LiveCapture` subscribes to a :class:`~lps_gui.capture.engine.CaptureEngine`'s
frame events and works on one thread beside it (cv2 releases the GIL):

* each listed frame is detected as ``lps detect`` would (the tracker starts
  again at the frames where :func:`~lps_gui.pipeline.detect.chunk_size` starts
  a chunk) and its block appended to corners.vnl (:mod:`lps_gui.io.corners.live`,
  fsynced; a resumed capture re-detects from the start of the killed chunk);
* every ``estimate_every`` views the views so far go through the one
  estimator (:func:`lps_gui.core.estimator.estimate.estimate`, warm-started from the
  previous solution) for the live deviation plot;
* the checks of :mod:`lps_gui.core.estimator.live_checks` run on every frame and every
  estimate; each finding is a :class:`LiveEvent` ("flag") at once.

When the plan completes, :meth:`LiveCapture.finish` writes corners.vnl in
``lps detect``'s form (the same bytes) and runs
:func:`lps_gui.pipeline.estimate.estimate_session`, the one path to
results, and the report when asked: the same numbers as a separate
``lps detect`` + ``lps estimate``, seconds after the last frame.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from lps_gui.capture.events import CaptureEvent, CaptureSummary
from lps_gui.core.estimator.estimate import estimate, views_against
from lps_gui.core.estimator.live_checks import EstimateChecks, FrameChecks, LiveFlag
from lps_gui.errors import LpsError
from lps_gui.hardware.stage import EventSource
from lps_gui.io.atomic import sha256_file
from lps_gui.io.corners.hashes import stat_meta
from lps_gui.io.corners.live import LiveView, open_live_corners
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.pipeline.detect import (
    ViewJob,
    ViewResult,
    board_key,
    chunk_size,
    default_workers,
    detect_view,
    session_corner_meta,
    session_corner_table,
    write_session_corners,
)
from lps_gui.io.results.keys import DEVIATION_UM, SIGMA_TOTAL_UM

log = logging.getLogger(__name__)

ESTIMATE_EVERY = 2  # views between running estimates: a fault is in an estimate within two stops
MIN_VIEWS = 4  # a line needs a few views spread along it


@dataclass(frozen=True)
class LiveEvent:
    """What the live results tell a CLI or GUI; listeners run on the live thread and must return quickly.

    ``kind``: "corners" (a view detected; ``data`` {method}), "estimate" (``data``: index, target_mm, direction,
    deviation_um, sigma_um, outlier lists over the views so far, rms_px, n_views), "flag" (``data``: the
    :class:`LiveFlag`), "results" (``data``: the results document), "report" (``data``: the PDF path),
    "error" (the live path failed; the capture goes on).
    """

    kind: str
    message: str = ""
    index: int | None = None
    data: Any = None


LiveListener = Callable[[LiveEvent], None]


@dataclass
class _Views:
    """The views detected so far, in capture order."""

    records: list[CaptureRecord] = field(default_factory=list)
    results: list[ViewResult] = field(default_factory=list)


class LiveCapture:
    """Live detection, running estimate and checks beside ``engine``; call :meth:`start`, run, :meth:`finish`."""

    def __init__(self, engine: Any, *, estimate_every: int = ESTIMATE_EVERY, workers: int | None = None,
                 method: str = "joint", options: dict[str, Any] | None = None) -> None:
        self.engine = engine
        self.session: Session = engine.session
        self.estimate_every = max(1, int(estimate_every))
        self.method, self.options = method, options
        board = self.session.board()
        self.board = board
        self.total = self.session.plan().n_frames()
        self.chunk = chunk_size(self.total, default_workers(workers))  # where `lps detect` starts a chunk
        self.image_size = None
        if self.session.has_intrinsics():
            try:
                self.image_size = self.session.intrinsics().image_size
            except LpsError as exc:  # as lps detect: no size check then
                log.warning("%s", exc)
        self._queue: queue.Queue[CaptureRecord | None] = queue.Queue()
        self._events = EventSource()
        self._views = _Views()
        self._file = None
        self._thread: threading.Thread | None = None
        self._tracker = None
        self._frame_checks = FrameChecks()
        self._estimate_checks = EstimateChecks()
        self._warm = None
        self._base_rms: float | None = None
        self._measured: tuple[Any, Any] | None = None  # (intrinsics, the board at its temperature, warped)
        self.flags: list[LiveFlag] = []
        self.last_estimate: dict[str, Any] | None = None
        self.error: str | None = None
        self._unsubscribe = engine.subscribe(self._on_capture_event)

    @staticmethod
    def unsupported(session: Session) -> str | None:
        """Why ``session`` cannot have live results, or None: a row or constellation of targets (SPEC 13) not yet."""
        if session.targets() is not None and not session.meta.get("board"):
            return (f"{session.folder}: live results take a single-board session; this one names targets "
                    "(run `lps detect` and `lps estimate` after the capture)")
        return None

    # ------------------------------------------------------------------ control
    def subscribe(self, listener: LiveListener) -> Callable[[], None]:
        return self._events.subscribe(listener)  # type: ignore[arg-type]

    def start(self) -> None:
        """Open corners.vnl (continuing a killed capture's), queue the listed frames it lacks, start the thread."""
        records = self.session.records()
        names = [r.file for r in records]
        key = board_key(self.board)
        self._file = open_live_corners(self.session.corners_path, key, self.board.n_corners, names)
        kept = len(self._file.views)
        restart = kept - kept % self.chunk  # the tracker of `lps detect` restarts only at a chunk's first frame
        if restart != kept:
            self._file.close()
            self._file = open_live_corners(self.session.corners_path, key, self.board.n_corners, names, keep=restart)
        by_name = {r.file: r for r in records}
        for view in self._file.views:
            self._views.records.append(by_name[view.name])
            self._views.results.append(ViewResult(view.name, view.corners_px, view.method, view.reason))
        for r in records[len(self._file.views):]:
            self._queue.put(r)
        self._thread = threading.Thread(target=self._work, name="lps-live", daemon=True)
        self._thread.start()

    def finish(self, summary: CaptureSummary | None = None, *, report: Path | bool = False,
               progress: Any = None) -> dict[str, Any] | None:
        """Wait for the detection of every listed frame; on a complete capture write corners.vnl as
        ``lps detect`` does, estimate the session (and write the report): the results document, else None."""
        from lps_gui.core.progress import no_progress

        self._queue.put(None)
        if self._thread is not None:
            self._thread.join()
        self._unsubscribe()
        if self._file is not None:
            self._file.close()
        if self.error is not None:
            raise LpsError(self.error)
        if summary is None or not summary.complete:
            return None
        self.write_final_corners()
        if not self.session.has_intrinsics():
            self._emit(LiveEvent("error", f"{self.session.folder}: corners.vnl written; no intrinsics to estimate with "
                                          "(give them with `lps estimate --intrinsics FILE`)"))
            return None
        from lps_gui.pipeline.estimate import estimate_session

        results = estimate_session(self.session.folder, self.method, self.options, progress=progress or no_progress)
        self._emit(LiveEvent("results", f"{self.session.folder / 'results.json'}", data=results))
        if report:
            from lps_gui.report.pdf.document import write_report

            out = None if report is True else Path(report)
            path = write_report(self.session.folder, results=results, out=out)
            self._emit(LiveEvent("report", str(path), data=str(path)))
        return results

    def write_final_corners(self) -> None:
        """corners.vnl in the form and bytes ``lps detect`` writes for the complete session."""
        records = self.session.records()
        names = [r.file for r in records]
        results = {res.name: res for res in self._views.results}
        meta = session_corner_meta(self.session, records, sha256_file(self.session.captures_path))
        meta.update(stat_meta(self.session.folder, names))
        write_session_corners(self.session, session_corner_table(names, results, self.board.n_corners, meta))

    # ------------------------------------------------------------------ the live thread
    def _on_capture_event(self, event: CaptureEvent) -> None:
        if event.kind == "frame" and event.record is not None:
            self._queue.put(CaptureRecord(**event.record))

    def _work(self) -> None:
        try:
            while (record := self._queue.get()) is not None:
                self._detect(record)
                # every few views, at the same views in every run (also a resumed one: flags are reproducible);
                # not at the plan's last frame: the final estimate follows at once
                done = len(self._views.results)
                if done % self.estimate_every == 0 and done < self.total:
                    self._estimate()
        except Exception as exc:  # the capture goes on; corners.vnl is rewritten by lps detect afterwards
            log.exception("live results failed")
            self.error = f"live results: {exc}; the capture is kept, run `lps detect` and `lps estimate` on it"
            self._emit(LiveEvent("error", self.error))
            while self._queue.get() is not None:  # drain: finish() must not wait forever
                pass

    def _detect(self, record: CaptureRecord) -> None:
        from lps_gui.camera.detection import ChessboardTracker, DetectionOptions, sharpness

        position = len(self._views.results)
        if position % self.chunk == 0 or self._tracker is None:
            self._tracker = ChessboardTracker(self.board, DetectionOptions(track=True))
        job = ViewJob(record.file, record.file, record.sha256, str(self.session.folder))
        result, image = detect_view(self._tracker, job, self.image_size)
        stat = stat_meta(self.session.folder, [record.file]).get(f"stat {record.file}")
        assert self._file is not None
        self._file.append(LiveView(result.name, result.corners_px, result.method, result.reason, record.sha256, stat))
        self._views.records.append(record)
        self._views.results.append(result)
        self._emit(LiveEvent("corners", result.method, record.index, {"method": result.method}))
        if image is not None:
            size = (image.shape[1], image.shape[0])
            for flag in self._frame_checks.check(record.index, result.corners_px, result.reason, float(image.mean()),
                                                 sharpness(image), size):
                self._flag(flag)

    def _estimate(self) -> None:
        """The views so far through the one estimator, warm-started; its checks."""
        from lps_gui.io.intrinsics_file import apply_board_warp
        from lps_gui.pipeline.estimate import make_options, observations_of_views
        from lps_gui.pipeline.session_input import session_board

        if self.session.planar or self.method != "joint" or not self.session.has_intrinsics():
            return
        views = self._views
        found = [r.corners_px is not None for r in views.results]
        if sum(found) < MIN_VIEWS:
            return
        n = self.board.n_corners
        corners = np.stack([np.full((n, 2), np.nan) if r.corners_px is None else np.asarray(r.corners_px, float)
                            for r in views.results])
        if self._measured is None:  # the session's intrinsics and board read once, not at every running estimate
            intr = self.session.intrinsics()
            self._measured = (intr, apply_board_warp(session_board(self.session), intr))
        intr, board = self._measured
        obs = observations_of_views(self.session.corners_path, board, intr, list(views.records), corners)
        opt = make_options("joint", {**(self.options or {}), "six_dof": False})
        t0 = time.perf_counter()
        if self._warm is not None and self._base_rms is not None:  # the new views against the solution so far
            new = np.arange(len(self._warm.s), obs.K)
            _, rms = views_against(self._warm, obs, new)
            for flag in self._estimate_checks.check_new_views(np.asarray(obs.index)[new], rms, self._base_rms):
                self._flag(flag)
        try:
            est = estimate(obs, opt, warm_start=self._warm)
        except LpsError as exc:  # too few or degenerate views so far: try again later
            log.info("running estimate skipped: %s", exc)
            self._warm = None
            return
        self._warm = est.state
        self._base_rms = float(np.nanmedian(np.where(est.used, est.rms_px, np.nan)))
        index = np.asarray(obs.index)
        dev = est.deviation_um(obs.target_mm)
        data = {"index": index.tolist(), "target_mm": np.asarray(obs.target_mm, float).tolist(),
                "direction": [r.direction for r in views.records],
                DEVIATION_UM: np.where(est.usable, dev, np.nan).tolist(), "sigma_um": (1e3 * est.sigma_s_mm).tolist(),
                SIGMA_TOTAL_UM: (1e3 * est.sigma_total_mm).tolist(),  # what the band draws (plots.drawn_sigma_um)
                "outlier": est.outlier.tolist(), "rms_px": est.rms_px.tolist(), "n_views": int(obs.K),
                "sigma_px": float(est.sigma_px), "seconds": time.perf_counter() - t0}
        self.last_estimate = data
        self._emit(LiveEvent("estimate", f"{obs.K} views, sigma {est.sigma_px:.3f} px", int(index[-1]), data))
        for flag in self._estimate_checks.check(index, est.outlier, est.outlier_reason):
            self._flag(flag)

    def _flag(self, flag: LiveFlag) -> None:
        self.flags.append(flag)
        self._emit(LiveEvent("flag", flag.message, flag.index, flag))

    def _emit(self, event: LiveEvent) -> None:
        self._events.emit(event)  # type: ignore[arg-type]  # a failing listener is logged, never stops the work
