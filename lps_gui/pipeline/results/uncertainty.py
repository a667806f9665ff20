"""Environment and uncertainty of a session's results (results.json ``environment``, ``uncertainty``).

For :mod:`lps_gui.pipeline.estimate`, for one axis or two:
:func:`environment_and_uncertainty` gives the environment record, the GUM budget
(:mod:`lps_gui.core.metrology.uncertainty_budget`; one per axis of a plane) and U
(k = 2) of every headline figure, from the values the estimate's builders made
(:class:`BudgetSource`, passed in: nothing is read back from the document being
built). The board at the measurement temperature (the thermal correction of the
length scale) is :attr:`lps_gui.pipeline.session_input.SessionInput.measured_board`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from lps_gui.core.metrology.environment import Environment, thermal_record
from lps_gui.core.metrology.uncertainty_budget import BudgetInputs, budget_rows, combine, figure_uncertainties
from lps_gui.io.results.sections import EnvironmentRecord, Uncertainty
from lps_gui.pipeline.session_input import SessionInput


def _column(positions: list[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else float(r[key]) for r in positions], dtype=float)


@dataclass(frozen=True)
class BudgetSource:
    """The estimate's values the budget is computed from, passed by the one who built them.

    ``positions``, ``parameters``, ``board``, ``figures`` and ``targets`` as results.json
    holds them; ``resolved``: the error motions' verdicts (None without error motions);
    ``stage_spec``: the data sheet; ``stitched``: one board moved between segments.
    """

    positions: list[dict[str, Any]]
    parameters: Mapping[str, Any]
    board: Mapping[str, Any]
    figures: Mapping[str, Any]
    axes: tuple[str, ...] = ("X",)
    resolved: Mapping[str, Any] | None = None
    targets: list[dict[str, Any]] | None = None
    stage_spec: Mapping[str, Any] | None = None
    stitched: bool = False

    @classmethod
    def of_results(cls, results: Mapping[str, Any]) -> "BudgetSource":
        """The values of a finished results.json document (a reader's re-computation)."""
        meta = results.get("session_meta") or {}
        return cls(positions=results.get("positions") or [], parameters=results.get("parameters") or {},
                   board=results.get("board") or {}, figures=results.get("figures") or {},
                   axes=tuple(results.get("axes") or ["X"]),
                   resolved=(results.get("error_motions") or {}).get("resolved"), targets=results.get("targets"),
                   stage_spec=meta.get("stage_spec") or results.get("stage_spec"),
                   stitched=bool((meta.get("plan") or {}).get("segments")))


def budget_inputs(src: BudgetSource, square_mm: float, axis: str = "") -> BudgetInputs:
    """BudgetInputs from the estimate's values: used views' sigmas, travel, board distance, pitch/yaw.

    ``axis``: "" for a line's columns (``sigma_um``), "x" or "y" for one axis of a planar session's
    (``sigma_x_um``); a plane has no per-view angles, so its Abbe row says so.
    """
    sfx = f"_{axis}" if axis else ""
    used = [r for r in src.positions
            if r.get("used", not r.get("outlier")) and r.get(f"deviation{sfx}_um") is not None]
    targets = _column(used, f"target{sfx}_mm")
    travel = float(np.nanmax(targets) - np.nanmin(targets)) if targets.size else 0.0
    p = src.parameters
    tilt = np.stack([_column(used, "pitch_urad"), _column(used, "yaw_urad")], axis=1) if used else None
    tilt_sig = np.stack([_column(used, "pitch_sigma_urad"), _column(used, "yaw_sigma_urad")], axis=1) if used else None
    if tilt is not None and not np.isfinite(tilt).any():
        tilt = tilt_sig = None
    return BudgetInputs(
        travel_mm=travel, square_mm=square_mm, sigma_px=float(p.get("sigma_px") or 0.0),
        sigma_um=_column(used, f"sigma{sfx}_um"), sigma_total_um=_column(used, f"sigma_total{sfx}_um"),
        sigma_lens_um=_column(used, "sigma_lens_um") if not axis and any("sigma_lens_um" in r for r in used) else None,
        abbe_lever_mm=abbe_lever_mm(p, src.board),
        tilt_urad=tilt, tilt_sigma_urad=tilt_sig, target_mm=targets, tilt_resolved=tilt_resolved(src.resolved))


def tilt_resolved(resolved: Mapping[str, Any] | None) -> tuple[bool, bool] | None:
    """Pitch (EBX) and yaw (ECX) resolved by the error motions (None when the session has none): the Abbe term
    takes only a resolved angle (issue 35: a lens misfit fakes a smooth tilt from one target plane)."""
    if not isinstance(resolved, Mapping) or not resolved:
        return None
    return (bool(resolved.get("EBX")), bool(resolved.get("ECX")))


def abbe_lever_mm(p: Mapping[str, Any], board: Mapping[str, Any]) -> tuple[float, float] | None:
    """(d, h): camera -> board centre along v2 (the lever of pitch) and along v1 (of yaw), mm.

    From the fitted line (results ``parameters``: R_cam_board, l0_cam_mm, u_board) and the board's size.
    """
    from lps_gui.core.models.lps_model import motion_frame

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


def environment_and_uncertainty(src: BudgetSource, session: SessionInput) -> tuple[EnvironmentRecord, Uncertainty]:
    """results.json ``environment`` and ``uncertainty`` of the estimate's values (``src.board`` with the
    nominal square size, :attr:`SessionInput.nominal_board`; the size used is ``environment.square_mm_used``)."""
    env = session.environment
    nominal = session.nominal_board  # a row's world frame is its first target
    return (EnvironmentRecord.of(**thermal_record(nominal, env)),
            Uncertainty.of(**uncertainty_section(src, env, nominal.square_mm)))


def uncertainty_of(results: Mapping[str, Any], env: Environment, square_mm: float) -> dict[str, Any]:
    """results.json ``uncertainty`` of a finished results.json document (:meth:`BudgetSource.of_results`)."""
    return uncertainty_section(BudgetSource.of_results(results), env, square_mm)


def uncertainty_section(src: BudgetSource, env: Environment, square_mm: float) -> dict[str, Any]:
    """results.json ``uncertainty``: budget, U (k = 2), U per headline figure; of each axis of a plane
    (``per_axis``: X and Y, the same sources as a line's)."""
    if len(src.axes) == 1:
        return _axis_uncertainty(src, env, square_mm, "", src.figures)
    planar = src.figures.get("planar") or {}
    axes = {name: (planar.get("per_axis") or {}).get(name) or {} for name in ("X", "Y")}
    return {"per_axis": {  # an axis's in-plane straightness is its v1: U of its p-v as a line's (verdict, page 1)
        name: _axis_uncertainty(src, env, square_mm, name.lower(),
                                {"single_run": {"scale_sigma_total_ppm": planar.get(f"scale_{name.lower()}_sigma_ppm")},
                                 "iso230_2": (a.get("iso230_2") or {}).get("iso230_2"),
                                 "straightness": {"v1": a.get("straightness") or {}}})
        for name, a in axes.items()}}


def _axis_uncertainty(src: BudgetSource, env: Environment, square_mm: float, axis: str,
                      figures: Mapping[str, Any]) -> dict[str, Any]:
    x = budget_inputs(src, square_mm, axis)
    rows = budget_rows(x, env)
    if src.stitched:  # one board moved: its one print is one scale (the board's row); the ties add repeatability
        from lps_gui.pipeline.stitched_session import stitch_row

        rows.append(stitch_row(src.targets, src.stage_spec))
    elif src.targets:  # each target's print enters the stretch measured against it (SPEC 13)
        from lps_gui.core.metrology.target_scale import target_scale_rows

        scale = target_scale_rows(src.targets, x.travel_mm, env.square_mm_uncertainty_um)
        at = next(k for k, r in enumerate(rows) if r.source == "board square size")
        rows[at:at + 1] = scale
    unc = combine(rows)
    unc["travel_mm"] = x.travel_mm
    used = [r for r in src.positions if not r.get("outlier")]
    key = f"target_{axis}_mm" if axis else "target_mm"
    targets = {round(float(r[key]), 6) for r in used if isinstance(r.get(key), (int, float))}
    angle_sigma = {name: float(np.nanmedian(s)) for name in ("roll", "pitch", "yaw")
                   if (s := _column(used, f"{name}_sigma_urad")).size and np.isfinite(s).any()}
    unc["figures_k2"] = figure_uncertainties(unc, figures, x.travel_mm, n_views=x.sigma_um.size,
                                             n_targets=len(targets), angle_sigma_urad=angle_sigma)
    return unc
