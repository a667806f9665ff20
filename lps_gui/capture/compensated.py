"""Compensated capture: the engine commands each target through a compensation table's inverse.

A controller without compensation of its own is corrected here: the target the
engine sends is ``table.command_mm(nominal, direction)``, the position at
which the table says the carriage really arrives at the nominal. The table
is stored in session.json so ``--resume`` goes on with the same correction.
"""
from __future__ import annotations

from pathlib import Path

from lps_gui.capture.engine import CaptureEngine
from lps_gui.core.metrology.compensation import CompensationTable
from lps_gui.io.compensation_file import read_table
from lps_gui.io.session import Session

META_KEY = "compensation"


def apply_compensation(engine: CaptureEngine, session: Session, path: Path | str | None) -> CompensationTable | None:
    """Bind the table in ``path`` (or the one the session was started with) to ``engine``; None without one."""
    if path:
        table = read_table(path)
        session.meta[META_KEY] = {"file": str(path), "table": table.to_dict()}
        session.save_meta()
    elif META_KEY in session.meta:
        table = CompensationTable.from_dict(session.meta[META_KEY]["table"])
    else:
        return None
    engine.command_of = lambda nominal_mm, direction: float(table.command_mm(nominal_mm, direction))
    return table
