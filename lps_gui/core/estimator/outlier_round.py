"""The outlier rounds of every estimator, whatever the number of axes (SPEC 4, SPEC 10).

A solve, then a judgement of the used views, then a solve without the
flagged ones, until a round flags nothing. The judgement is one rule for D
= 1 and 2: a *bumped* camera does not fit the common rotation (its RMS
reprojection error stands out, :func:`~lps_gui.core.numerics.outliers.reprojection_outliers`);
a *replaced* image fits but its position leaves the trend of the others
(the model of D axes says which trend). Flagged views are listed with the
reason and the round, never dropped silently.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from lps_gui.core.estimator.estimate_types import EstimateOptions
from lps_gui.core.numerics.outliers import reprojection_outliers
from lps_gui.core.progress import CancelToken
from lps_gui.errors import DegenerateGeometryError

MIN_VIEWS_LEFT = 3  # fewer views than this after removing outliers determine neither a line nor a plane

# valid views -> (moved (K,) bool, the reason of view i): the D-axis model's position test
PositionTest = Callable[[np.ndarray], tuple[np.ndarray, Callable[[int], str]]]


@dataclass
class Solution:
    """Where the solve and the outlier rounds stand: what the uncertainty step starts from."""

    state: Any  # LpsState (D = 1) or PlanarState (D = 2)
    ref: int  # the gauge view (position 0): first usable view not flagged
    usable: np.ndarray  # (K,) board found
    outlier: np.ndarray  # (K,) flagged
    reasons: list[str]
    flags: list[dict[str, Any]] = field(default_factory=list)
    iterations: int = 0
    converged: bool = False
    equations: Any = None  # the last solve's normal equations when the judgement can reuse them

    @property
    def used(self) -> np.ndarray:
        return self.usable & ~self.outlier

    def free(self) -> np.ndarray:
        """Positions the solve moves: used views but the gauge view."""
        free = self.used.copy()
        free[self.ref] = False
        return free


def judge_views(sol: Solution, rms: np.ndarray, position_test: PositionTest, index: np.ndarray, k: float,
                round_no: int, source: str) -> bool:
    """Flag bumped cameras and replaced images among the used views once; True if any is new."""
    used = sol.used
    bumped = reprojection_outliers(rms, used, k)
    moved, position_reason = position_test(used & ~bumped)
    new = (bumped | moved) & ~sol.outlier
    for i in np.flatnonzero(new):
        if bumped[i]:
            sol.reasons[i] = (f"reprojection RMS {rms[i]:.3f} px against a median of {np.median(rms[used]):.3f} px "
                              "(camera bumped?)")
            kind = "reprojection"
        else:
            sol.reasons[i] = position_reason(i)
            kind = "position"
        sol.flags.append({"index": int(index[i]), "kind": kind, "message": sol.reasons[i], "round": round_no})
    if not new.any():
        return False
    sol.outlier |= new
    if sol.used.sum() < MIN_VIEWS_LEFT:  # before a new gauge view is chosen: every view may be flagged
        raise DegenerateGeometryError(f"{source}: fewer than {MIN_VIEWS_LEFT} views are left after removing outliers "
                                      f"({int(sol.used.sum())} of {int(sol.usable.sum())}); check the capture, or raise "
                                      "the outlier threshold k")
    if sol.outlier[sol.ref]:
        sol.ref = int(np.flatnonzero(sol.used)[0])
    return True


def solve_with_outliers(sol: Solution, solve: Callable[[Solution], None], judge: Callable[[Solution, int], bool],
                        opt: EstimateOptions, timings: dict[str, float], cancel: CancelToken | None = None) -> Solution:
    """Solve, then up to ``opt.max_outlier_rounds + 1`` judgements; one that flags views is followed by a solve
    without them."""
    def timed_solve() -> None:
        if cancel is not None:
            cancel.check("estimation")
        t0 = time.perf_counter()
        solve(sol)
        timings["solve"] = timings.get("solve", 0.0) + time.perf_counter() - t0

    timed_solve()
    for round_no in range(1, opt.max_outlier_rounds + 2):
        if not opt.detect_outliers or not judge(sol, round_no):
            break
        timed_solve()
    return sol
