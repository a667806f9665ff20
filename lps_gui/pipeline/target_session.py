"""A session with targets (SPEC 13) on the one estimation path: its observations and its results section.

:func:`lps_gui.pipeline.estimate.observations_from_session` comes here for a
session.json that names ``targets``: the SPEC 13 corners.vnl is read, checked
like a board's (stale images, missing views, collinear views) and laid out as
one set of corners per view with each corner's target
(``Observations.mounted``). :func:`targets_with_truth` makes results.json
``targets``: each target's pose in the world frame (target 0's) with its
sigma, the views that saw it and that tie it, and its share of the travel
(what its print's scale enters in the budget, :mod:`lps_gui.core.metrology.target_scale`).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.core.estimator.observations import Observations
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.geometry.targets import Target, target_offsets
from lps_gui.core.metrology.environment import corrected_board
from lps_gui.core.metrology.target_scale import covered_fractions
from lps_gui.errors import InputError
from lps_gui.io.corners.target_vnl import read_target_corners
from lps_gui.io.results.sections import TargetRecord
from lps_gui.pipeline.results.targets import MIN_CORNERS, target_rows
from lps_gui.pipeline.session_checks import corners_of_records
from lps_gui.pipeline.session_input import SessionInput


def measured_targets(session: SessionInput) -> list[Target]:
    """The session's targets as the estimator uses them: each square at its certified scale
    (``scale_ppm``) and at the session's temperature (environment)."""
    env = session.environment
    out = []
    for t in session.targets or []:
        board = t.board
        if t.scale_ppm:
            board = replace(board, square_mm=board.square_mm * (1.0 + 1e-6 * t.scale_ppm))
        out.append(replace(t, board=corrected_board(board, env)))
    return out


def target_observations(session: SessionInput, intrinsics: CameraIntrinsics, records: list, approach: list | None
                        ) -> Observations:
    """Observations of every capture against the session's targets (corners laid end to end)."""
    targets = measured_targets(session)
    if not session.corners_path.is_file():
        raise InputError(f"{session.corners_path}: corners file not found; run `lps detect` first")
    table = read_target_corners(session.corners_path, targets)
    corners = without_collinear_targets(corners_of_records(session, table, records, views_whole=False),
                                        target_offsets(targets))
    return Observations(
        board=targets[0].board, intrinsics=intrinsics, corners_px=corners,
        target_mm=[r.target_mm for r in records],
        direction=[1.0 if r.direction == "+" else -1.0 for r in records],
        run=[r.run for r in records], index=[r.index for r in records], names=[r.file for r in records],
        source=str(session.corners_path), source_sha256=table.sha256, approach=approach, mounted=tuple(targets))


def without_collinear_targets(corners_px: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The corners with each target's dropped from the views where they lie on one line (a target cut by
    the image border to one row or column fixes no pose of its own); the rest of those views is kept."""
    from lps_gui.core.geometry.view_geometry import collinear_views

    out = corners_px
    for a, b in zip(offsets[:-1], offsets[1:]):
        bad = collinear_views(corners_px[:, a:b])
        if bad:
            out = out.copy() if out is corners_px else out
            out[np.ix_(bad, np.arange(a, b))] = np.nan
    return out


def seen_by_target(obs: Observations, used: np.ndarray) -> np.ndarray:
    """(K, T) bool: the used views that saw each target (at least MIN_CORNERS of its corners)."""
    offsets = target_offsets(list(obs.mounted))
    ok = np.isfinite(obs.corners_px[..., 0])
    counts = np.add.reduceat(ok, offsets[:-1], axis=1)
    return (counts >= MIN_CORNERS) & np.asarray(used, bool)[:, None]


def targets_section(obs: Observations, est: Any, session: SessionInput) -> list[dict[str, Any]]:
    """results.json ``targets`` (SPEC 13)."""
    fit = est.fit_targets
    rows = target_rows(list(obs.mounted), fit.Q, fit.p, fit.target_sigma, obs.corners_px, obs.targets, est.used)
    seen = seen_by_target(obs, est.used)
    several = seen.sum(axis=1) >= 2
    share = covered_fractions(seen)
    nominal = {t.id: t for t in session.targets or []}
    printed = [nominal.get(t.id, t) for t in obs.mounted]
    return [{  # new rows: target_rows' rows are left as they were (a builder returns values, issue 34)
        **row, "square_mm": pr.board.square_mm,
        **({} if pr.square_mm_uncertainty_um is None else {"square_mm_uncertainty_um": pr.square_mm_uncertainty_um}),
        **({} if pr.scale_ppm is None else {"scale_ppm": pr.scale_ppm}),
        "covered_fraction": float(share[j]),
        "seen_by": obs.index[seen[:, j]].astype(int).tolist(),  # capture indices
        "tied_by": obs.index[seen[:, j] & several].astype(int).tolist(),
    } for j, (row, pr) in enumerate(zip(rows, printed))]


def targets_with_truth(obs: Observations, est: Any, session: SessionInput
                       ) -> tuple[list[dict[str, Any]], dict[str, Any] | None]:
    """results.json ``targets`` and, for a simulated session, ``truth_comparison.targets`` (each pose compared with
    the simulator's; None for a real one): values, which the caller writes (its place is
    :data:`lps_gui.io.results.document.SECTIONS`')."""
    from lps_gui.sim.truth import target_truth_comparison

    section = [TargetRecord.of(**row).to_dict() for row in targets_section(obs, est, session)]  # as readers read it
    return section, target_truth_comparison(session, section)
