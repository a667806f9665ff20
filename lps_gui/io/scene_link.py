"""How a scene session names the measurement session it relies on (issue 38, SPEC 17).

A light field takes its positions and rotations from a measured stage, so the scene session's
session.json carries ``scene.measurement_session``: the measured folder (absolute), its creation time and
the sha256 of the results.json in force when the scene was captured. ``lps lightfield`` opens the
measurement through this link and records which results it used.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.file_limits import read_file_limited
from lps_gui.io.atomic import sha256_bytes
from lps_gui.io.results.document import RESULTS_FILE
from lps_gui.io.session import Session

SCENE_KEY = "scene"


def results_sha256(session: Session) -> str:
    """sha256 of the measurement's results.json; a one-line error when it has none yet."""
    path = session.folder / RESULTS_FILE
    if not path.is_file():
        raise InputError(f"{session.folder}: no {RESULTS_FILE}; estimate the measurement first (lps estimate "
                         f"{session.folder})")
    return sha256_bytes(read_file_limited(path, what="results file", follow_symlinks=False))


def measurement_link(measured: Session) -> dict[str, Any]:
    """The id of a measurement session as a scene session records it."""
    return {"path": str(measured.folder.resolve()), "created": measured.meta.get("created"),
            "results_sha256": results_sha256(measured)}


def linked_measurement(scene: Session, override: Path | str | None = None) -> tuple[Session, dict[str, Any]]:
    """The measurement session a scene session names (or ``override``), and the id it is known by now."""
    link = (scene.meta.get(SCENE_KEY) or {}).get("measurement_session")
    if override is None and not isinstance(link, dict):
        raise InputError(f"{scene.folder}: not a scene session (no scene.measurement_session in session.json); "
                         "capture one with `lps capture --scene MEASURED_SESSION --out DIR`")
    folder = Path(override) if override is not None else Path(str(link.get("path")))
    if not (folder / "session.json").is_file():
        raise InputError(f"{scene.folder}: its measurement session {folder} is gone; give it with --measurement DIR")
    measured = Session.open(folder)
    return measured, measurement_link(measured)
