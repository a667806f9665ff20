"""A stitched session on the one estimation path: one board moved between overlapping segments (SPEC 13).

session.json names its one ``board`` and a plan with ``segments``; captures.jsonl
gives each capture's ``segment``; corners.vnl is the board's (detection as
for any board). Here each segment's placement of the board becomes a target
(``S0``, ``S1``, ...: the same geometry, its own unknown pose) with the view's
corners in that target's place, so :func:`lps_gui.core.estimator.estimate.estimate`
solves it as a row whose ties are the stops repeated across a boundary
(:mod:`lps_gui.core.estimator.stitching`). The stage's repeatability that those ties
rest on is 1/4 of the specified repeatability R (session.json
``stage_spec.repeatability_um``; ISO 230-2: R = 4 s); without it the ties'
term is not stated and not in U.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.core.estimator.observations import Observations
from lps_gui.core.estimator.stitching import segment_ties, stitch_budget_row
from lps_gui.core.geometry.targets import Target
from lps_gui.core.metrology.uncertainty_budget import BudgetRow
from lps_gui.errors import InputError
from lps_gui.pipeline.session_input import SessionInput

SEGMENT_PREFIX = "S"  # the targets of a stitched session: S0, S1, ... one per placement of the board
R_PER_SIGMA = 4.0  # ISO 230-2: the repeatability R of a direction is 4 s


def stage_repeatability_mm(spec: dict[str, Any] | None) -> float | None:
    """The stage's repeatability (1 sigma, mm) from its specification's R, or None when not stated."""
    r = (spec or {}).get("repeatability_um")
    return None if r is None else float(r) / R_PER_SIGMA * 1e-3


def stitched_observations(session: SessionInput, obs: Observations, records: list) -> Observations:
    """The board session's observations as a row of one target per segment."""
    missing = next((r for r in records if r.segment is None), None)
    if missing is not None:
        raise InputError(f"{session.captures_path}: capture {missing.index} names no segment; a stitched plan "
                         "(plan.segments) lists each capture's segment")
    segment = np.array([r.segment for r in records], int)
    n_seg = int(segment.max()) + 1
    board = obs.board if obs.board.type == "charuco" else replace(obs.board, type="charuco")  # geometry only
    targets = tuple(Target(f"{SEGMENT_PREFIX}{k}", board, 0) for k in range(n_seg))
    n = board.n_corners
    corners = np.full((obs.K, n * n_seg, 2), np.nan)
    corners[np.arange(obs.K)[:, None], segment[:, None] * n + np.arange(n)] = obs.corners_px
    return replace(obs, corners_px=corners, mounted=targets, segment=segment,
                   repeatability_mm=stage_repeatability_mm(session.meta.get("stage_spec")))


def with_stitch_ties(targets: list[dict[str, Any]], obs: Observations) -> list[dict[str, Any]]:
    """results.json ``targets`` of a stitched session, as new rows (``targets`` is left as it was): each placement
    is tied by its repeated stops, not by views that see two boards; ``stitch_ties`` counts the pairs tying it to
    the placement before."""
    ties = segment_ties(obs.targets, obs.segment)
    tied: list[set[int]] = [set() for _ in targets]
    for b, pairs in enumerate(ties):
        tied[b].update(pairs[:, 0].tolist())
        tied[b + 1].update(pairs[:, 1].tolist())
    index = np.asarray(obs.index)
    return [{**row, "ties": len(views), "tied_by": index[views].astype(int).tolist(),
             "stitch_ties": len(ties[k - 1]) if k else 0}
            for k, (row, views) in enumerate(zip(targets, (sorted(t) for t in tied)))]


def stitch_row(targets: list[dict[str, Any]] | None, stage_spec: dict[str, Any] | None) -> BudgetRow:
    """The budget row of the ties (over the whole travel) from results.json's targets and the stage spec."""
    counts = [t.get("stitch_ties", 0) for t in (targets or [])[1:]]
    sigma = stage_repeatability_mm(stage_spec)
    return stitch_budget_row([np.zeros((c, 2), int) for c in counts], None if sigma is None else 1e3 * sigma)
