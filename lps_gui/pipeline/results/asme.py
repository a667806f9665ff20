"""results.json ``asme_b5_64``: the ASME B5.64 tests of a line session, from the one estimate.

Every session gets the ISO 230-2 figures under both names with their test
uncertainty ratio (the data sheet's tolerance, session.json ``stage_spec``,
over U of the figure as the verdict compares it: one rule,
:func:`lps_gui.core.metrology.verdict.verdicts`; no tolerance, no ratio). A session
whose ``asme_test`` names the incremental-step or the settling test (the
plan presets of :mod:`lps_gui.core.planning.presets`) also gets that test's figures:
stops averaged over their frames, each step's sigma from the estimate's full
covariance; position against each frame's time after its move
(captures.jsonl ``since_move_s``).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.core.estimator.estimate import EstimateOptions, LpsEstimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.metrology.asme_b5_64 import (
    StopMeans,
    incremental_step_figures,
    incremental_steps,
    named_figures,
    settling_figures,
    tur,
)
from lps_gui.core.truth.stage_errors import StageErrorModel, Vibration
from lps_gui.io.results.model import Results
from lps_gui.io.results.sections import AsmeB564, Uncertainty
from lps_gui.pipeline.results.verdict import measured
from lps_gui.pipeline.session_input import SessionInput

SPEC_TOLERANCES = {"incremental_step": ("min_incremental_motion_um", "\u00b5m"),
                   "settling": ("settling_time_s", "s")}  # stage_spec keys of the ASME tests' tolerances


def test_options(session: SessionInput, options: EstimateOptions) -> EstimateOptions:
    """The estimate's options for a session's ASME test: a settling test's frames ring by design, so the
    outlier test (a view off its neighbours' positions) is off there; every other session as given."""
    if (session.meta.get("asme_test") or {}).get("test") == "settling" and options.detect_outliers:
        return replace(options, detect_outliers=False)
    return options


def asme_results(session: SessionInput, obs: Observations, est: LpsEstimate, figures: Mapping[str, Any],
                 uncertainty: Uncertainty) -> AsmeB564:
    """results.json ``asme_b5_64`` of a line session from its figures and their U (k = 2), as the builders made
    them (after the uncertainty budget: the ratios need U); the ratios are the verdict's rows of those values."""
    section: dict[str, Any] = {"figures": named_figures(figures.get("iso230_2"), uncertainty.get("figures_k2") or {})}
    test = session.meta.get("asme_test") or {}
    records = {r.index: r for r in session.records}
    if test.get("test") == "min-step":
        section["incremental_step"] = incremental_step_section(obs, est, records, session, test)
    elif test.get("test") == "settling":
        section["settling"] = settling_section(obs, est, records, session, test)
    spec = session.meta.get("stage_spec") or {}
    section["test_uncertainty_ratio"] = tur_rows(measured(("X",), figures, uncertainty, AsmeB564.of(**section)), spec)
    return AsmeB564.of(**section)  # as the readers read it


def tur_rows(values: Results, spec: dict[str, Any]) -> list[dict[str, Any]]:
    """Per specified figure: tolerance, U (k = 2) of the figure compared, and their ratio (None without U); the verdict's
    rows of ``values`` (:func:`lps_gui.pipeline.results.verdict.measured`), the ASME test's own (min-step, settling)
    among them."""
    from lps_gui.core.metrology.verdict import verdicts

    return [{"figure": v.name, "quantity": v.quantity, "tolerance": v.limit, "U": v.u_k2, "unit": v.unit,
             "tur": tur(v.limit, v.u_k2)} for v in (verdicts(values, spec) if spec else [])]


def stop_keys(obs: Observations, records: dict[int, Any]) -> np.ndarray:
    """Each view's stop: the capture index of the stop's first frame, shape (K,)."""
    return np.array([i - int(getattr(records.get(i), "frame", 0) or 0) for i in np.asarray(obs.index).tolist()])


def stop_means(obs: Observations, est: LpsEstimate, keys: np.ndarray) -> tuple[StopMeans, list[np.ndarray]]:
    """The stops with the positions of their used frames averaged, and each stop's frames (view numbers)."""
    used = np.asarray(est.used, dtype=bool)
    s_mm = est.state.s + obs.target_mm[est.reference_view]
    order = [np.flatnonzero((keys == k) & used) for k in np.unique(keys)]
    order = [v for v in order if v.size]
    first = np.array([v[0] for v in order])
    direction = np.asarray(obs.direction, dtype=float)[first]
    run = np.asarray(obs.run)[first]
    return StopMeans(
        target_mm=np.asarray(obs.target_mm, dtype=float)[first],
        position_mm=np.array([s_mm[v].mean() for v in order]),
        direction=np.sign(direction).astype(int),
        pass_id=run.astype(int) * 2 + (direction > 0),
        n_frames=np.array([v.size for v in order]),
    ), order


def incremental_step_section(obs: Observations, est: LpsEstimate, records: dict[int, Any], session: SessionInput,
                             test: dict[str, Any]) -> dict[str, Any]:
    """The incremental-step test: each step between consecutive averaged stops of one pass."""
    stops, frames = stop_means(obs, est, stop_keys(obs, records))
    i, j = incremental_steps(stops)
    sigma = []
    for a, b in zip(i, j):
        row = np.zeros(obs.K)
        row[frames[b]] = 1.0 / frames[b].size
        row[frames[a]] -= 1.0 / frames[a].size
        sigma.append(1e3 * est.linear_functional_sigma(row)[0])
    commanded = 1e3 * (stops.target_mm[j] - stops.target_mm[i])
    achieved = 1e3 * (stops.position_mm[j] - stops.position_mm[i])
    out = incremental_step_figures(commanded, achieved, np.array(sigma), float(test.get("tolerance", 0.5)))
    out["steps"] = [{**row, "from_mm": float(stops.target_mm[a]), "to_mm": float(stops.target_mm[b]),  # new rows
                     "direction": "+" if stops.direction[b] > 0 else "-"} for row, a, b in zip(out["steps"], i, j)]
    out["frames_per_stop"] = int(np.median(stops.n_frames)) if stops.n_frames.size else 0
    out["planned_step_um"] = test.get("step_um")
    truth = _truth_errors(session)
    if truth is not None:
        out["truth"] = {"dead_band_um": truth.dead_band_um}
    return out


def settling_section(obs: Observations, est: LpsEstimate, records: dict[int, Any], session: SessionInput,
                     test: dict[str, Any]) -> dict[str, Any]:
    """The settling test: each stop's positions against its frames' time after the move, and the time to settle."""
    band = float(test.get("band_um", 5.0))
    keys = stop_keys(obs, records)
    s_um = 1e3 * (est.state.s + obs.target_mm[est.reference_view])
    usable = np.asarray(est.usable, dtype=bool)
    since = np.array([np.nan if getattr(records.get(i), "since_move_s", None) is None else records[i].since_move_s
                      for i in np.asarray(obs.index).tolist()], dtype=float)
    per_stop = []
    for k in np.unique(keys):
        v = np.flatnonzero((keys == k) & usable & np.isfinite(since))
        if v.size < 8:
            continue
        sign = 1.0 if obs.direction[v[0]] > 0 else -1.0
        x = sign * (s_um[v] - 1e3 * obs.target_mm[v[0]])  # along the move: the first swing overshoots
        fig = settling_figures(since[v], x, band)
        if fig is None:
            continue
        per_stop.append({**fig, "target_mm": float(obs.target_mm[v[0]]), "direction": "+" if sign > 0 else "-",
                         "since_move_s": since[v].tolist(), "position_um": (x - fig["rest_um"]).tolist()})
    out: dict[str, Any] = {"band_um": band, "n_stops": len(per_stop), "stops": per_stop}
    if per_stop:
        worst = max(per_stop, key=lambda f: f["settling_time_s"])
        out.update(settling_time_s=worst["settling_time_s"], settling_time_U_s=worst["settling_time_U_s"],
                   settling_time_frames_s=worst["settling_time_frames_s"],
                   median_settling_time_s=float(np.median([f["settling_time_s"] for f in per_stop])))
    ring = _truth_vibration(session)
    if ring is not None:
        out["truth"] = {**ring.to_dict(), "settling_time_s": ring.settling_time_s(band)}
    return out


def _truth_errors(session: SessionInput) -> StageErrorModel | None:
    truth = session.meta.get("truth") or {}
    return StageErrorModel.from_dict(truth["stage_errors"]) if isinstance(truth.get("stage_errors"), dict) else None


def _truth_vibration(session: SessionInput) -> Vibration | None:
    """The simulated stage's ringing: the point simulator's truth, or the simulated stage's description."""
    truth = session.meta.get("truth") or {}
    if not truth:
        return None
    ring = truth.get("vibration") or (session.meta.get("stage") or {}).get("vibration")
    return Vibration.from_dict(ring) if isinstance(ring, dict) else None
