"""The session as the estimate path reads it, once: the value every results builder is given.

:func:`read_session_input` opens session.json, captures.jsonl and (for a
simulated session) the simulator's truth one time; the observations, the
results builders (:mod:`lps_gui.pipeline.results`) and the targets' and
stitching sections take their board, plan, targets, environment, records and
truth from this frozen value instead of re-opening the session, so the files
cannot change under one estimate and each is parsed once.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.targets import Target
from lps_gui.core.metrology.environment import Environment, corrected_board
from lps_gui.core.planning.plan import Plan
from lps_gui.io.intrinsics_file import read_intrinsics
from lps_gui.io.session import SESSION_FILE, CaptureRecord, Session


@dataclass(frozen=True)
class SessionInput:
    """What one estimate reads of a session folder (``session`` kept for its paths and the write-side checks).

    ``board`` is the nominal board (None for a row or constellation: ``targets``);
    ``truth`` is the simulator's truth reduced by :func:`lps_gui.sim.truth.session_truth`
    (None for a real session); ``meta`` is session.json as read.
    """

    session: Session
    meta: Mapping[str, Any]
    intrinsics: CameraIntrinsics
    records: tuple[CaptureRecord, ...]
    environment: Environment
    targets: tuple[Target, ...] | None
    board: Board | None
    plan: Plan
    truth: dict[str, Any] | None

    @property
    def folder(self) -> Path:
        return self.session.folder

    @property
    def corners_path(self) -> Path:
        return self.session.corners_path

    @property
    def captures_path(self) -> Path:
        return self.session.captures_path

    @property
    def planar(self) -> bool:
        return self.session.planar

    @property
    def nominal_board(self) -> Board:
        """The board of the session's world frame at 20 C: its one board, or a row's first target's."""
        return self.board if self.targets is None else self.targets[0].board

    @property
    def measured_board(self) -> Board:
        """The one board with its square size at the board's temperature (the thermal correction)."""
        return corrected_board(self.board, self.environment)


def session_environment(session: Session) -> Environment:
    """session.json ``environment`` parsed (empty when absent)."""
    return Environment.from_dict(session.meta.get("environment"), f"{session.folder / SESSION_FILE}: environment")


def session_board(session: Session) -> Board:
    """The one board of a session with its square size at the board's temperature (a live estimate's)."""
    return corrected_board(session.board(), session_environment(session))


def read_session_input(session_dir: Path | str | Session, intrinsics_path: Path | str | None = None,
                       intrinsics: CameraIntrinsics | None = None) -> SessionInput:
    """Read a session folder once for an estimate (``intrinsics_path`` or ``intrinsics`` instead of the session's)."""
    from lps_gui.sim.truth import session_truth

    session = session_dir if isinstance(session_dir, Session) else Session.open(session_dir)
    if intrinsics is None:
        intrinsics = read_intrinsics(intrinsics_path) if intrinsics_path else session.intrinsics()
    records = tuple(session.records())
    targets = session.targets()
    return SessionInput(
        session=session, meta=session.meta, intrinsics=intrinsics, records=records,
        environment=session_environment(session), targets=None if targets is None else tuple(targets),
        board=session.board() if session.meta.get("targets") is None else None, plan=session.plan(),
        truth=session_truth(session))
