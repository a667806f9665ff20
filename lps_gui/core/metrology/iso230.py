"""Accuracy figures of SPEC section 5 (ISO 230-2 style) as pure math.

Deviations x = measured - target (um) of captures grouped by target P_j,
approach direction (up "+" / down "-") and run feed three sets of figures:

* :func:`bidirectional_figures` -- ISO 230-2 figures across runs: systematic
  deviation E, mean reversal B, range of mean bidirectional deviation M,
  repeatability R and accuracy A, per direction and bidirectional.
* :func:`single_run_figures` -- one run (or all data): mean step, step std,
  max |deviation|, linear scale error (ppm) and the periodic error (spectrum of
  the detrended deviations; a lead-screw pitch shows as the peak).
* :func:`figures_for_session` -- both, as JSON-ready dicts for results.json.

:func:`check_specification` compares them with a stage's data sheet.
No I/O, no Qt: numpy and scipy only.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.metrology.iso230_run import (
    DEVIATION,
    TARGET_TOL_MM,
    JsonDataclass,
    RunFigures,
    capture_arrays,
    finite_or_none,
    json_value,
    single_run_figures,
    target_index,
)
from lps_gui.core.metrology.resolution import ISO_RUNS_PER_DIRECTION, is_indicative, straightness_verdict
from lps_gui.errors import InputError

__all__ = ["TARGET_TOL_MM", "ApproachPlan", "Iso230Figures", "RunFigures", "TargetTable", "approach_plan",
           "bidirectional_figures", "check_specification", "direction_signs", "figures_for_session", "plan_figures",
           "single_run_figures"]

ISO_RUNS = 5  # ISO 230-2 asks for 5 runs per direction
RUN_STATISTIC_ROWS = ("Positional accuracy", "Repeatability")  # specification rows that are ISO 230-2 run statistics


# ----------------------------------------------------------------------------- input normalisation


def direction_signs(direction: Any) -> np.ndarray:
    """Directions ``"+"/"-"`` (also "up"/"down", "forward"/"backward") or +-1 -> int array of +1/-1."""
    d = np.asarray(direction)
    if d.dtype.kind in "iuf":
        sign = np.sign(d.astype(float))
        if np.any(sign == 0) or not np.all(np.isfinite(sign)):
            raise InputError("direction: use +1/-1 (or '+'/'-') for every capture; found 0 or NaN")
        return sign.astype(int)
    words = {"+": 1, "up": 1, "forward": 1, "+1": 1, "1": 1, "-": -1, "down": -1, "backward": -1, "-1": -1}
    out = np.array([words.get(str(e).strip().lower(), 0) for e in d.ravel()], dtype=int).reshape(d.shape)
    if np.any(out == 0):
        bad = d.ravel()[np.flatnonzero(out.ravel() == 0)[0]]
        raise InputError(f"direction: {bad!r} is not '+' or '-'; give '+'/'-' or +1/-1 per capture")
    return out


def _session_arrays(target_mm: Any, direction: Any, run: Any, deviation_um: Any, valid: Any
                    ) -> dict[str, np.ndarray]:
    """Per-capture arrays of shape (K,) with ``sign`` (+1/-1) and ``run`` (all 0 when None)."""
    a = capture_arrays(target_mm, deviation_um, valid, run=np.zeros(np.size(target_mm), int) if run is None else run,
                       direction=direction_signs(direction))
    a["sign"] = a.pop("direction").astype(int)
    return a


# ----------------------------------------------------------------------------- ISO 230-2 bidirectional


@dataclass
class TargetTable(JsonDataclass):
    """Per-target statistics of SPEC 5 (arrays of shape (m,), NaN where undefined)."""

    target_mm: np.ndarray
    n_up: np.ndarray  # runs approaching P_j upward
    n_down: np.ndarray
    mean_up_um: np.ndarray  # x̄_j↑: mean deviation over runs
    mean_down_um: np.ndarray
    std_up_um: np.ndarray  # s_j↑ (ddof=1), needs 2 runs
    std_down_um: np.ndarray
    reversal_um: np.ndarray  # B_j = x̄_j↑ - x̄_j↓
    R_up_um: np.ndarray  # R_j↑ = 4 s_j↑
    R_down_um: np.ndarray
    R_um: np.ndarray  # R_j = max(2 s_j↑ + 2 s_j↓ + |B_j|, R_j↑, R_j↓)


@dataclass
class Iso230Figures(JsonDataclass):
    """ISO 230-2 figures of SPEC 5 (um); None where the runs do not define them (see ``notes``)."""

    n_targets: int
    n_runs_up: int
    n_runs_down: int
    E_up_um: float | None  # systematic deviation ↑: max x̄↑ - min x̄↑
    E_down_um: float | None
    E_um: float | None  # bidirectional systematic deviation: over both directions
    M_um: float | None  # range of mean bidirectional deviation (x̄↑ + x̄↓)/2
    B_um: float | None  # reversal error: max |B_j|
    B_mean_um: float | None  # mean reversal error: mean of B_j
    R_up_um: float | None  # unidirectional repeatability ↑: max R_j↑
    R_down_um: float | None
    R_um: float | None  # bidirectional repeatability: max R_j
    A_up_um: float | None  # accuracy ↑: max(x̄↑ + 2s↑) - min(x̄↑ - 2s↑)
    A_down_um: float | None
    A_um: float | None  # bidirectional accuracy over both directions
    per_target: TargetTable
    notes: list[str] = field(default_factory=list)


def _span(v: np.ndarray) -> float | None:
    """max - min, None if ``v`` is empty."""
    return float(v.max() - v.min()) if v.size else None


def _band(mean: np.ndarray, std: np.ndarray) -> float | None:
    """max(x̄ + 2s) - min(x̄ - 2s) over targets where s is defined (the accuracy A)."""
    return float((mean + 2 * std).max() - (mean - 2 * std).min()) if mean.size else None


def _max(v: np.ndarray) -> float | None:
    return float(v.max()) if v.size else None


@dataclass(frozen=True)
class _Direction:
    """The approaches of one direction: their targets, and per target how many (mean from 1, std from 2)."""

    target: np.ndarray  # (n,) target index of each approach
    n: np.ndarray  # (m,) approaches per target, float
    has: np.ndarray  # (m,) n >= 1: x̄_j defined
    two: np.ndarray  # (m,) n >= 2: s_j defined

    @classmethod
    def of(cls, target: np.ndarray, m: int) -> _Direction:
        n = np.bincount(target, minlength=m).astype(float)
        return cls(target, n, n >= 1, n >= 2)

    def stats(self, dev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(mean, std ddof=1) per target of the approaches' deviations ``dev``; NaN where undefined."""
        m = self.n.size
        mean, std = np.full(m, np.nan), np.full(m, np.nan)
        mean[self.has] = np.bincount(self.target, dev, minlength=m)[self.has] / self.n[self.has]
        ss = np.bincount(self.target, (dev - mean[self.target]) ** 2, minlength=m)
        std[self.two] = np.sqrt(ss[self.two] / (self.n[self.two] - 1.0))
        return mean, std


@dataclass(frozen=True)
class ApproachPlan:
    """How :func:`bidirectional_figures` groups a plan's captures into approaches (target, direction, run).

    Why separate: the grouping depends on the plan only (targets, directions, runs, validity), not on the
    deviations; the noise Monte Carlo (iso230_noise) evaluates hundreds of deviation draws of one plan.
    """

    valid: np.ndarray  # (K,) the captures used
    targets: np.ndarray  # (m,) targets ascending
    capture_approach: np.ndarray  # (K used,) approach of each used capture
    frames: np.ndarray  # (n,) frames averaged into each approach
    approach_up: np.ndarray  # (n,) bool: an upward approach
    up: _Direction
    down: _Direction
    runs_up: int
    runs_down: int


def _approach_plan(t: np.ndarray, r: np.ndarray, sign: np.ndarray, ok: np.ndarray) -> ApproachPlan:
    """The plan of the used captures (``t``, ``r``, ``sign`` already masked by ``ok``)."""
    targets, j = target_index(t)
    # one approach = (target, direction, run): its frames are averaged first
    _, run_id = np.unique(r, return_inverse=True)
    n_runs = run_id.max() + 1
    appr_key = (j * 2 + (sign > 0)) * n_runs + run_id.ravel()
    keys, inv, cnt = np.unique(appr_key, return_inverse=True, return_counts=True)
    approach_target, up = keys // n_runs // 2, ((keys // n_runs) % 2).astype(bool)
    return ApproachPlan(valid=ok, targets=targets, capture_approach=inv.ravel(), frames=cnt, approach_up=up,
                        up=_Direction.of(approach_target[up], targets.size),
                        down=_Direction.of(approach_target[~up], targets.size),
                        runs_up=int(np.unique(r[sign > 0]).size), runs_down=int(np.unique(r[sign < 0]).size))


def approach_plan(target_mm: np.ndarray, direction: np.ndarray, run: np.ndarray,
                  valid: np.ndarray | None = None) -> ApproachPlan | None:
    """The grouping of :func:`bidirectional_figures` for captures whose deviations are all finite; None: none valid."""
    a = _session_arrays(target_mm, direction, run, np.zeros(np.size(target_mm)), valid)
    ok = a["valid"]
    if not ok.any():
        return None
    return _approach_plan(a["target_mm"][ok], a["run"][ok], a["sign"][ok], ok)


def plan_figures(plan: ApproachPlan, deviation_um: np.ndarray) -> tuple[TargetTable, dict[str, float | None]] | None:
    """Per-target table and the ISO figures (the float fields of :class:`Iso230Figures`) of one deviation set.

    ``deviation_um`` has shape (K,) as the plan's captures; None when a used capture's deviation is not
    finite (its plan would differ: :func:`bidirectional_figures` leaves it out).
    """
    x = np.asarray(deviation_um, dtype=float).ravel()[plan.valid]
    if not np.isfinite(x).all():
        return None
    u, d, is_up = plan.up, plan.down, plan.approach_up
    appr_dev = np.bincount(plan.capture_approach, x) / plan.frames
    mean_up, std_up = u.stats(appr_dev[is_up])
    mean_dn, std_dn = d.stats(appr_dev[~is_up])
    reversal = mean_up - mean_dn  # NaN unless both directions
    both = u.has & d.has
    R_up_j, R_dn_j = 4 * std_up, 4 * std_dn
    R_j = np.fmax(np.fmax(2 * std_up + 2 * std_dn + np.abs(reversal), R_up_j), R_dn_j)
    r_ok = u.two & d.two & both
    R_j[~r_ok] = np.nan
    table = TargetTable(plan.targets, u.n.astype(int), d.n.astype(int), mean_up, mean_dn, std_up, std_dn, reversal,
                        R_up_j, R_dn_j, R_j)
    return table, dict(
        E_up_um=_span(mean_up[u.has]), E_down_um=_span(mean_dn[d.has]),
        E_um=_span(np.concatenate([mean_up[u.has], mean_dn[d.has]])),
        M_um=_span(((mean_up + mean_dn) / 2)[both]),
        B_um=_max(np.abs(reversal[both])), B_mean_um=float(reversal[both].mean()) if both.any() else None,
        R_up_um=_max(R_up_j[u.two]), R_down_um=_max(R_dn_j[d.two]), R_um=_max(R_j[r_ok]),
        A_up_um=_band(mean_up[u.two], std_up[u.two]), A_down_um=_band(mean_dn[d.two], std_dn[d.two]),
        A_um=_band(np.concatenate([mean_up[u.two], mean_dn[d.two]]), np.concatenate([std_up[u.two], std_dn[d.two]]))
        if (u.two.any() and d.two.any()) else None)


def bidirectional_figures(target_mm: np.ndarray, direction: np.ndarray, run: np.ndarray,
                          deviation_um: np.ndarray, valid: np.ndarray | None = None) -> Iso230Figures | None:
    """ISO 230-2 positioning figures (SPEC section 5) from captures of several runs.

    Parameters
    ----------
    target_mm : shape (K,), target P_j of each capture; targets within 1e-6 mm are one target.
    direction : shape (K,), approach direction, "+"/"-" or +1/-1.
    run : shape (K,), run id; several frames of one run at one target are averaged into one approach.
    deviation_um : shape (K,), x = measured - target.
    valid : shape (K,) bool or None; False (outliers) and NaN deviations are left out.

    Returns
    -------
    Iso230Figures, or None when no valid capture is left. Figures the data do not
    define (std with one run per direction; B, M, bidirectional R and A with one
    direction) are None, and ``notes`` says why.
    """
    a = _session_arrays(target_mm, direction, run, deviation_um, valid)
    ok = a["valid"]
    if not ok.any():
        return None
    plan = _approach_plan(a["target_mm"][ok], a["run"][ok], a["sign"][ok], ok)
    table, figures = plan_figures(plan, a[DEVIATION])
    return Iso230Figures(n_targets=int(plan.targets.size), n_runs_up=plan.runs_up, n_runs_down=plan.runs_down,
                         **figures, per_target=table,
                         notes=_iso_notes(table, plan.runs_up, plan.runs_down, int((~ok).sum())))


def _iso_notes(tab: TargetTable, runs_up: int, runs_dn: int, n_invalid: int) -> list[str]:
    """Why some figures are missing or indicative, in words for the report."""
    notes = []
    if n_invalid:
        notes.append(f"{n_invalid} capture(s) left out as invalid (outliers or no position).")
    if runs_up == 0 or runs_dn == 0:
        have = "upward (+)" if runs_up else "downward (-)"
        notes.append(f"Only {have} approaches: reversal B, mean range M and bidirectional R and A are undefined.")
    for name, runs, std in (("upward", runs_up, tab.std_up_um), ("downward", runs_dn, tab.std_down_um)):
        if runs == 1:
            notes.append(f"One {name} run only: its standard deviation (n-1 = 0) and so R and A are undefined.")
        elif runs > 1 and not np.isfinite(std).all():
            k = int((~np.isfinite(std)).sum())
            notes.append(f"{k} target(s) reached by fewer than 2 {name} runs are left out of {name} R and A.")
    if 0 < min(runs_up or ISO_RUNS, runs_dn or ISO_RUNS) < ISO_RUNS:
        notes.append(f"ISO 230-2 asks for {ISO_RUNS} runs per direction; with fewer the figures are indicative.")
    return notes


# ----------------------------------------------------------------------------- a whole session


def figures_for_session(target_mm: np.ndarray, direction: np.ndarray, run: np.ndarray,
                        deviation_um: np.ndarray, valid: np.ndarray | None = None,
                        sigma_um: np.ndarray | None = None) -> dict[str, Any]:
    """All SPEC 5 figures of a session as JSON-ready dicts (results.json ``figures``).

    Returns
    -------
    dict with ``"single_run"`` (:func:`single_run_figures` of all valid captures, one
    offset per run and direction), ``"per_run"`` (list of ``{"run", "direction",
    "figures"}`` per run and direction) and ``"iso230_2"`` (:func:`bidirectional_figures`
    as a dict when at least 2 runs in one direction or both directions exist, else None).
    """
    a = _session_arrays(target_mm, direction, run, deviation_um, valid)
    r, sign = a["run"], a["sign"]
    pairs, group = np.unique(np.stack([r.astype(str), sign.astype(str)], axis=1), axis=0, return_inverse=True)
    sig = None if sigma_um is None else np.asarray(sigma_um, dtype=float).ravel()
    single = single_run_figures(a["target_mm"], a[DEVIATION], a["valid"], sig, group=group.ravel())
    order = sorted(range(len(pairs)), key=lambda i: (_run_sort_key(r[group.ravel() == i][0]), -int(pairs[i][1])))
    per_run = []
    for i in order:
        sel = group.ravel() == i
        figs = single_run_figures(a["target_mm"][sel], a[DEVIATION][sel], a["valid"][sel],
                                  None if sig is None else sig[sel])
        run_value = r[sel][0]
        per_run.append({"run": json_value(run_value.item() if hasattr(run_value, "item") else run_value),
                        "direction": "+" if int(pairs[i][1]) > 0 else "-", "figures": figs.to_dict()})
    ok = a["valid"]
    runs_per_dir = [np.unique(r[ok & (sign == s)]).size for s in (1, -1)]
    iso = None
    if max(runs_per_dir) >= 2 or min(runs_per_dir) >= 1:
        fig = bidirectional_figures(a["target_mm"], sign, r, a[DEVIATION], ok)
        iso = None if fig is None else fig.to_dict()
    return {"single_run": single.to_dict(), "per_run": per_run, "iso230_2": iso}


def _run_sort_key(v: Any) -> tuple[int, Any]:
    try:
        return (0, float(v))
    except (TypeError, ValueError):
        return (1, str(v))


# ----------------------------------------------------------------------------- specification


def _bi_or_uni(iso: dict[str, Any], letter: str, word: str) -> tuple[float | None, str]:
    """The bidirectional ISO figure ``letter``, else the larger unidirectional one, with its name."""
    value = finite_or_none(iso.get(f"{letter}_um"))
    if value is not None:
        return value, f"ISO 230-2 bidirectional {word} {letter}"
    uni = [v for v in (finite_or_none(iso.get(f"{letter}_up_um")), finite_or_none(iso.get(f"{letter}_down_um")))
           if v is not None]
    return (max(uni), f"ISO 230-2 unidirectional {word} {letter}") if uni else (None, "")


def check_specification(figures: dict[str, Any], spec: dict[str, Any]) -> list[dict[str, Any]]:
    """Pass/fail of a stage data sheet (the paper's Table 1) against SPEC 5 figures.

    ``spec`` keys (each optional): ``accuracy_um``, ``repeatability_um``,
    ``straightness_um``, and ``limits``: ``"plus_minus"`` (default: the data sheet
    reads "Accuracy +-20 um") or ``"band"`` (limits are full widths).

    Choices, since the deviation's zero (the first capture) is arbitrary:

    * accuracy: the ISO band A (bidirectional, else the wider unidirectional A;
      with one run per direction, the span max x - min x of all valid deviations,
      or 2 max |x| for results that carry no span);
      against a +- limit we compare the half band A/2 (the band centred).
    * repeatability: R (bidirectional, else the larger of R↑, R↓); R/2 against a
      +- limit. Undefined with one run per direction (``passed`` None).
    * straight-line accuracy: ``figures["straightness_um_max"]`` (largest
      peak-to-valley straightness, given by the estimator) against the limit as a
      full width in both modes (the data sheet gives it without +-). Noise only
      inflates a peak-to-valley, so a pass stands; a fail while the per-view
      noise alone spans the limit (4 x ``figures["straightness_sigma_um"]``)
      is "not resolved" (``passed`` None), not a verdict on the stage.

    With ``figures["straightness"]`` (board-plane spans with their noise p-v)
    the straight-line row comes from :func:`core.resolution.straightness_verdict`.
    Every row carries ``indicative``: True when fewer runs per direction than
    ISO 230-2 asks (5) back the figures; such a verdict is not a FAIL.

    Returns
    -------
    list of ``{"name", "measured", "limit", "unit", "passed", "note", "indicative"}`` rows;
    ``passed`` is None when the session does not measure (or resolve) the figure.
    """
    mode = str(spec.get("limits", "plus_minus"))
    if mode not in ("plus_minus", "band"):
        raise InputError(f"stage spec: limits must be 'plus_minus' or 'band', got {mode!r}")
    half = 0.5 if mode == "plus_minus" else 1.0
    versus = " / 2 vs \u00b1limit" if half < 1 else " vs band limit"
    iso = figures.get("iso230_2") or {}
    single = figures.get("single_run") or {}
    rows = []

    def limit(key: str) -> float | None:
        if spec.get(key) is None:
            return None
        try:
            return float(spec[key])
        except (TypeError, ValueError):
            raise InputError(f"stage spec: {key} must be a number in um, got {spec[key]!r}") from None

    def row(name: str, measured: float | None, lim: float, note: str) -> dict[str, Any]:
        return {"name": name, "measured": measured, "limit": lim, "unit": "\u00b5m",
                "passed": None if measured is None else bool(measured <= lim), "note": note}

    lim = limit("accuracy_um")
    if lim is not None:
        value, what = _bi_or_uni(iso, "A", "accuracy")
        if value is None:
            value, what = finite_or_none(single.get("deviation_span_um")), "deviation span max x - min x (one run)"
        if value is None and finite_or_none(single.get("max_abs_deviation_um")) is not None:
            value, what = 2.0 * float(single["max_abs_deviation_um"]), "2 max |x| (one run, no span given)"
        rows.append(row("Positional accuracy", None if value is None else value * half, lim,
                        what + versus if value is not None else "no accuracy figures in these results"))
    lim = limit("repeatability_um")
    if lim is not None:
        value, what = _bi_or_uni(iso, "R", "repeatability")
        rows.append(row("Repeatability", None if value is None else value * half, lim,
                        what + versus if value is not None else "needs two or more runs per direction"))
    lim = limit("straightness_um")
    verdict = None if lim is None else straightness_verdict(figures, lim)
    if verdict is not None:
        rows.append({"name": "Straight-line accuracy", "limit": lim, "unit": "\u00b5m", **verdict})
    elif lim is not None:
        spans = [finite_or_none(v) for v in np.ravel(np.asarray(figures.get("straightness_um_max"), dtype=object))]
        spans = [v for v in spans if v is not None]
        value = max(spans) if spans else None
        r = row("Straight-line accuracy", value, lim,
                "largest peak-to-valley straightness vs limit" if value is not None
                else "no straightness figures in these results")
        noise = finite_or_none(figures.get("straightness_sigma_um"))
        if r["passed"] is False and noise is not None and 4.0 * noise >= lim:
            r["passed"] = None
            r["note"] = f"not resolved: noise alone spans ~{4 * noise:.0f} \u00b5m (per-view \u03c3 {noise:.1f} \u00b5m)"
        rows.append(r)
    indicative = is_indicative(figures)
    for r in rows:
        # ISO 230-2's 5 runs per direction are for its run statistics; straightness averages the runs it has
        r["indicative"] = indicative and r["name"] in RUN_STATISTIC_ROWS
        if r["indicative"] and r["passed"] is not None:
            r["note"] += f"; indicative: fewer than {ISO_RUNS_PER_DIRECTION} runs per direction"
    return rows
