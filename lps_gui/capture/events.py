"""What a running capture tells the outside world: its state, progress, events and final summary.

The engine never calls GUI code: a GUI polls :meth:`CaptureEngine.progress`
on a timer (every field is a plain value, safe to read from any thread) or
subscribes to :class:`CaptureEvent` callbacks, which run on the engine's
thread and must return quickly.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

# Engine states
IDLE = "idle"  # constructed, run() not called yet
RUNNING = "running"
PAUSED = "paused"  # by the user (run() waits) or by an error (run() returned; call run() again)
DONE = "done"  # every planned frame is listed in captures.jsonl
ABORTED = "aborted"  # abort() or the cancel token; everything listed is kept
STATES = (IDLE, RUNNING, PAUSED, DONE, ABORTED)


@dataclass(frozen=True)
class CaptureEvent:
    """Something that happened during a capture.

    ``kind`` is one of "started", "approach", "move", "frame", "paused",
    "resumed", "error", "done", "aborted", "warning" (a stop that did not
    settle in time), "move board" (a stitched plan's next segment: the
    capture pauses until the board is moved and it is resumed); ``index`` is the capture index
    concerned (None when not about one frame); ``record`` is the
    captures.jsonl line as a dict for "frame" events.
    """

    kind: str
    message: str = ""
    index: int | None = None
    record: dict[str, Any] | None = None


CaptureListener = Callable[[CaptureEvent], None]


@dataclass(frozen=True)
class CaptureProgress:
    """A snapshot of a capture for a progress bar or a status line.

    ``done`` and ``total`` count frames of the whole plan (frames listed in
    an earlier, interrupted run count as done); ``eta_s`` is in the engine's
    clock (simulated seconds under a SimClock), None until a frame was taken.
    """

    state: str
    done: int
    total: int
    eta_s: float | None = None
    index: int | None = None  # capture index being worked on
    target_mm: float | None = None
    message: str = ""
    error: str | None = None

    @property
    def fraction(self) -> float:
        return 0.0 if self.total <= 0 else min(1.0, self.done / self.total)


@dataclass(frozen=True)
class CaptureSummary:
    """What :meth:`CaptureEngine.run` returns.

    ``captured`` counts frames written by this call; ``listed`` all frames in
    captures.jsonl; ``error`` is the one-line reason of an error pause.
    """

    state: str
    captured: int
    listed: int
    total: int
    elapsed_s: float  # engine clock
    folder: str
    error: str | None = None

    @property
    def complete(self) -> bool:
        return self.state == DONE
