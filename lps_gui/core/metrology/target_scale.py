"""Each target's printed scale in the uncertainty budget (SPEC 13).

Every length of a target session is in units of the printed squares, but of
which target depends on where the camera was: a scale error of target j
enters only the stretch of travel measured against it. A view that sees
several targets shares its part of the travel equally among them, so target
j covers L_j = L * (sum_i w_ij) / (sum_ij w_ij) of the travel L (w_ij = 1 / the
number of targets view i sees), the L_j add up to L, and its print's
uncertainty u_j (um per square of s_j mm) enters a displacement over the
travel as (L_j / s_j) u_j. The prints are independent, so the rows add in
quadrature like every other row of the budget.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.core.metrology.uncertainty_budget import BudgetRow

SOURCE_PREFIX = "target scale"


def covered_fractions(seen: np.ndarray) -> np.ndarray:
    """The share of the travel each target covers, shape (T,), from which views see it (K, T) bool."""
    seen = np.asarray(seen, bool)
    n = seen.sum(axis=1, keepdims=True)
    w = np.where(n > 0, seen / np.maximum(n, 1), 0.0).sum(axis=0)
    return w / w.sum() if w.sum() > 0 else w


def target_scale_rows(targets: list[dict[str, Any]], travel_mm: float, fallback_um: float | None = None
                      ) -> list[BudgetRow]:
    """One budget row per target from results.json ``targets`` (``covered_fraction``, ``square_mm``,
    ``square_mm_uncertainty_um``); ``fallback_um`` for a target without its own (environment's)."""
    rows = []
    for t in targets:
        length = float(t.get("covered_fraction") or 0.0) * travel_mm
        squares = length / float(t["square_mm"])
        u = t.get("square_mm_uncertainty_um", fallback_um)
        name = f"{SOURCE_PREFIX} {t['id']}"
        where = f"{length:.0f} mm of the travel measured against it ({squares:.1f} squares)"
        if u is None:
            rows.append(BudgetRow(name, "B", None, "\u00b5m", squares, None,
                                  f"print scale not stated (the target's certificate); {where}; not in U"))
        else:
            rows.append(BudgetRow(name, "B", float(u), "\u00b5m", squares, squares * float(u),
                                  f"print scale of {t['id']}; {where}"))
    return correlation_stated(rows)


def correlation_stated(rows: list[BudgetRow]) -> list[BudgetRow]:
    """The first stated row's note says how the targets' print scales combine: as independent prints (root sum of
    squares, as the budget does); one printer for all would correlate them fully and add them linearly (GUM 5.2)."""
    stated = [r.contribution_um for r in rows if r.contribution_um is not None]
    if len(stated) < 2:
        return rows
    rss, linear = float(np.sqrt(np.sum(np.square(stated)))), float(np.sum(np.abs(stated)))
    first = next(i for i, r in enumerate(rows) if r.contribution_um is not None)
    note = (f"{rows[first].note}; the {len(stated)} print scales are combined as independent prints (uncorrelated: "
            f"{rss:.3g} \u00b5m together); if one printer made them all they are correlated and add linearly "
            f"({linear:.3g} \u00b5m)")
    return [*rows[:first], replace(rows[first], note=note), *rows[first + 1:]]
