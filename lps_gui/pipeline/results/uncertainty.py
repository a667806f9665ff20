"""Environment and uncertainty of a session's results (results.json ``environment``, ``uncertainty``).

Two hooks for :mod:`lps_gui.pipeline.estimate`, for one axis or two:
:func:`session_board` gives the board at the measurement temperature (the
thermal correction of the length scale, :mod:`lps_gui.core.metrology.environment`),
and :func:`add_uncertainty` adds the environment record, the GUM budget
(:mod:`lps_gui.core.metrology.uncertainty_budget`; one per axis of a plane) and U
(k = 2) of every headline figure to a finished results dict. The budget is built from results.json
alone, so it does not depend on how the estimate is assembled.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.metrology.environment import Environment, corrected_board, thermal_record
from lps_gui.core.metrology.uncertainty_budget import BudgetInputs, budget_rows, combine, figure_uncertainties
from lps_gui.io.session import SESSION_FILE, Session


def session_environment(session: Session) -> Environment:
    """session.json ``environment`` parsed (empty when absent)."""
    return Environment.from_dict(session.meta.get("environment"), f"{session.folder / SESSION_FILE}: environment")


def session_board(session: Session) -> Board:
    """The session's board with its square size corrected to the board's temperature."""
    return corrected_board(session.board(), session_environment(session))


def _column(positions: list[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else float(r[key]) for r in positions], dtype=float)


def budget_inputs(results: dict[str, Any], square_mm: float, axis: str = "") -> BudgetInputs:
    """BudgetInputs from results.json: used views' sigmas, travel, board distance, pitch/yaw.

    ``axis``: "" for a line's columns (``sigma_um``), "x" or "y" for one axis of a planar session's
    (``sigma_x_um``); a plane has no per-view angles, so its Abbe row says so.
    """
    sfx = f"_{axis}" if axis else ""
    used = [r for r in results.get("positions") or []
            if r.get("used", not r.get("outlier")) and r.get(f"deviation{sfx}_um") is not None]
    targets = _column(used, f"target{sfx}_mm")
    travel = float(np.nanmax(targets) - np.nanmin(targets)) if targets.size else 0.0
    p = results.get("parameters") or {}
    tilt = np.stack([_column(used, "pitch_urad"), _column(used, "yaw_urad")], axis=1) if used else None
    tilt_sig = np.stack([_column(used, "pitch_sigma_urad"), _column(used, "yaw_sigma_urad")], axis=1) if used else None
    if tilt is not None and not np.isfinite(tilt).any():
        tilt = tilt_sig = None
    return BudgetInputs(
        travel_mm=travel, square_mm=square_mm, sigma_px=float(p.get("sigma_px") or 0.0),
        sigma_um=_column(used, f"sigma{sfx}_um"), sigma_total_um=_column(used, f"sigma_total{sfx}_um"),
        sigma_lens_um=_column(used, "sigma_lens_um") if not axis and any("sigma_lens_um" in r for r in used) else None,
        abbe_lever_mm=abbe_lever_mm(results),
        tilt_urad=tilt, tilt_sigma_urad=tilt_sig, target_mm=targets, tilt_resolved=tilt_resolved(results))


def tilt_resolved(results: dict[str, Any]) -> tuple[bool, bool] | None:
    """Pitch (EBX) and yaw (ECX) resolved by the error motions (None when the session has none): the Abbe term
    takes only a resolved angle (issue 35: a lens misfit fakes a smooth tilt from one target plane)."""
    resolved = (results.get("error_motions") or {}).get("resolved")
    if not isinstance(resolved, dict) or not resolved:
        return None
    return (bool(resolved.get("EBX")), bool(resolved.get("ECX")))


def abbe_lever_mm(results: dict[str, Any]) -> tuple[float, float] | None:
    """(d, h): camera -> board centre along v2 (the lever of pitch) and along v1 (of yaw), mm.

    From the fitted line (results ``parameters``: R_cam_board, l0_cam_mm, u_board) and the board's size.
    """
    from lps_gui.core.models.lps_model import motion_frame

    p = results.get("parameters") or {}
    board = results.get("board") or {}
    try:
        R = np.asarray(p["R_cam_board"], float)
        l0 = np.asarray(p["l0_cam_mm"], float)
        frame = motion_frame(R, np.asarray(p["u_board"], float))
        cols, rows = board.get("inner_corners") or (2, 2)
        centre = 0.5 * float(board.get("square_mm") or 0.0) * np.array([cols - 1, rows - 1, 0.0])
    except (KeyError, TypeError, ValueError):
        return None
    r = centre + R.T @ l0  # board centre minus camera centre, in the board frame
    return float(abs(r @ frame[:, 2])), float(abs(r @ frame[:, 1]))


def add_uncertainty(results: dict[str, Any], session: Session) -> dict[str, Any]:
    """Add ``environment`` and ``uncertainty`` to results (in place; also returned).

    ``board.square_mm`` stays the nominal (20 C) size; the size used is in
    ``environment.square_mm_used``.
    """
    env = session_environment(session)
    targets = session.targets()
    nominal = session.board() if targets is None else targets[0].board  # a row's world frame is its first target
    results["environment"] = thermal_record(nominal, env)
    if isinstance(results.get("board"), dict):
        results["board"]["square_mm"] = nominal.square_mm
    results["uncertainty"] = uncertainty_of(results, env, nominal.square_mm)
    return results


def uncertainty_of(results: dict[str, Any], env: Environment, square_mm: float) -> dict[str, Any]:
    """results.json ``uncertainty``: budget, U (k = 2), U per headline figure; of each axis of a plane
    (``per_axis``: X and Y, the same sources as a line's)."""
    if len(results.get("axes") or ["X"]) == 1:
        return _axis_uncertainty(results, env, square_mm, "", results.get("figures") or {})
    planar = (results.get("figures") or {}).get("planar") or {}
    axes = {name: (planar.get("per_axis") or {}).get(name) or {} for name in ("X", "Y")}
    return {"per_axis": {  # an axis's in-plane straightness is its v1: U of its p-v as a line's (verdict, page 1)
        name: _axis_uncertainty(results, env, square_mm, name.lower(),
                                {"single_run": {"scale_sigma_total_ppm": planar.get(f"scale_{name.lower()}_sigma_ppm")},
                                 "iso230_2": (a.get("iso230_2") or {}).get("iso230_2"),
                                 "straightness": {"v1": a.get("straightness") or {}}})
        for name, a in axes.items()}}


def _axis_uncertainty(results: dict[str, Any], env: Environment, square_mm: float, axis: str,
                      figures: dict[str, Any]) -> dict[str, Any]:
    x = budget_inputs(results, square_mm, axis)
    rows = budget_rows(x, env)
    stitched = bool(((results.get("session_meta") or {}).get("plan") or {}).get("segments"))
    if stitched:  # one board moved: its one print is one scale (the board's row); the ties add repeatability
        from lps_gui.pipeline.stitched_session import stitch_row

        rows.append(stitch_row(results))
    elif results.get("targets"):  # each target's print enters the stretch measured against it (SPEC 13)
        from lps_gui.core.metrology.target_scale import target_scale_rows

        scale = target_scale_rows(results["targets"], x.travel_mm, env.square_mm_uncertainty_um)
        at = next(k for k, r in enumerate(rows) if r.source == "board square size")
        rows[at:at + 1] = scale
    unc = combine(rows)
    unc["travel_mm"] = x.travel_mm
    used = [r for r in results.get("positions") or [] if not r.get("outlier")]
    key = f"target_{axis}_mm" if axis else "target_mm"
    targets = {round(float(r[key]), 6) for r in used if isinstance(r.get(key), (int, float))}
    angle_sigma = {name: float(np.nanmedian(s)) for name in ("roll", "pitch", "yaw")
                   if (s := _column(used, f"{name}_sigma_urad")).size and np.isfinite(s).any()}
    unc["figures_k2"] = figure_uncertainties(unc, figures, x.travel_mm, n_views=x.sigma_um.size,
                                             n_targets=len(targets), angle_sigma_urad=angle_sigma)
    return unc
