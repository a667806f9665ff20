"""Per-capture truth of a simulated rig: truth.jsonl while capturing, session.json's ``truth`` at the end.

The simulated stage knows where the carriage really was at each grab. The
engine appends that to ``truth.jsonl`` (durably, before the capture's own
line, so every listed frame has its truth) and, once the plan is complete,
folds it into session.json in the layout of :func:`core.simulate.true_views`
(``index``, ``axis_mm``, ``positions_mm`` relative to the first capture,
``straightness_um`` (K, 2), ``angles_urad`` (K, 3), in capture-index order).
A resumed capture may append a line twice for one index; the last one wins.
"""
from __future__ import annotations

import json
from typing import Any

from lps_gui.core.stage_errors import TruePose
from lps_gui.io.atomic import append_line_durable, write_text_atomic
from lps_gui.io.session import Session

TRUTH_FILE = "truth.jsonl"


def pose_truth(pose: TruePose) -> dict[str, Any]:
    """A one-carriage :class:`TruePose` (K=1) as a JSON-able dict."""
    return {
        "axis_mm": float(pose.axis_mm.ravel()[0]),
        "straightness_um": [float(v) for v in pose.straightness_um.reshape(-1)[:2]],
        "angles_urad": [float(v) for v in pose.angles_urad.reshape(-1)[:3]],
    }


def append_truth(session: Session, index: int, truth: dict[str, Any]) -> None:
    """Append the truth of capture ``index`` to truth.jsonl (fsynced)."""
    line = json.dumps({"index": int(index), **truth}, separators=(",", ":"))
    append_line_durable(session.folder / TRUTH_FILE, line)


def read_truth(session: Session) -> dict[int, dict[str, Any]]:
    """Truth per capture index from truth.jsonl (last line per index wins; a torn line is ignored)."""
    path = session.folder / TRUTH_FILE
    if not path.exists():
        return {}
    out: dict[int, dict[str, Any]] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            d = json.loads(line)
            out[int(d["index"])] = d
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            continue  # a crash tore it; the capture it belongs to was not listed
    return out


def prune_truth(session: Session) -> None:
    """Keep only the truth lines of listed captures (once each): run before a capture (re)starts.

    A crash between a frame's truth line and its capture line leaves a line
    for a frame that is not listed (or a torn one); the resumed capture
    takes that frame again, so without pruning its index would appear twice.
    """
    path = session.folder / TRUTH_FILE
    if not path.exists():
        return
    listed = {r.index for r in session.records()}
    per_index = read_truth(session)
    keep = [per_index[i] for i in sorted(per_index) if i in listed]
    text = "".join(json.dumps(d, separators=(",", ":")) + "\n" for d in keep)
    if text != path.read_text(encoding="utf-8"):
        write_text_atomic(path, text)


def finalize_truth(session: Session) -> None:
    """Write the per-capture truth of every listed capture into session.json's ``truth``."""
    per_index = read_truth(session)
    indices = sorted({r.index for r in session.records()} & set(per_index))
    if not indices:
        return
    rows = [per_index[i] for i in indices]
    axis = [float(r["axis_mm"]) for r in rows]
    truth = dict(session.meta.get("truth") or {})
    truth.update(
        {
            "index": indices,
            "axis_mm": axis,
            "positions_mm": [a - axis[0] for a in axis],
            "straightness_um": [list(r["straightness_um"]) for r in rows],
            "angles_urad": [list(r["angles_urad"]) for r in rows],
        }
    )
    session.meta["truth"] = truth
    session.save_meta()
