"""A capture plan as plain data: which targets, in which order, how often, on one or two axes.

A one-axis plan is a grid with one axis (SPEC 7): targets from ``start_mm``
to ``stop_mm`` by ``step_mm`` (or explicit ``targets_mm``), visited upward
on a forward pass and downward on a backward one. A two-axis plan (an XY
gantry, SPEC 10) is a grid over both axes (``start_mm``, ``stop_mm``,
``step_mm`` as [x, y], serpentine or raster) or explicit ``targets_mm``
[[x, y], ...] in visiting order; its backward pass visits them in reverse.

ISO 230-2 approaches every target from its own side, per axis: the approach
side of an axis at a stop is the sign of its last move, and a pass' first
stop is reached from an overshoot on the side of each axis' first move. On
one axis that is the pass' own direction.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator, NamedTuple

import numpy as np

from lps_gui.core.planning.limits import check_plan_fields
from lps_gui.errors import InputError

DIRECTIONS = ("+", "-", "both")
PATTERNS = ("serpentine", "raster")
MAX_PLANAR_TARGETS = 100_000
MOVE_TOL_MM = 1e-9
LINE_FIELDS = ("start_mm", "stop_mm", "step_mm", "targets_mm", "directions", "runs", "overshoot_mm", "settle_s",
               "frames_per_stop", "feed_mm_min")  # a one-axis plan's session.json fields, in their order


def run_directions(directions: str) -> list[str]:
    """The passes of a run: "both" is forward then backward."""
    return ["+", "-"] if directions == "both" else [directions]


class PlannedStop(NamedTuple):
    """One frame to capture: its place in the session and its target."""

    index: int
    run: int
    direction: str  # "+" forward pass, "-" backward pass
    target_mm: float | tuple[float, float]  # a number on one axis, (x, y) on two (captures.jsonl keeps that form)
    frame: int  # 0 .. frames_per_stop-1
    approach: tuple[int, ...] = ()  # +1 / -1 per axis: the side each axis reached the target from
    segment: int | None = None  # a stitched plan's segment (the board is moved between segments); None otherwise


def _pair(v: Any, name: str) -> tuple[float, float]:
    try:
        a = np.asarray(v, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"planar plan: {name} must be [x, y] in mm, got {v!r}") from None
    if a.size != 2 or not np.all(np.isfinite(a)):
        raise InputError(f"planar plan: {name} must be two finite numbers [x, y] in mm, got {v!r}")
    return float(a[0]), float(a[1])


def _is_pair(v: Any) -> bool:
    return isinstance(v, (list, tuple, np.ndarray))


def _axes_of(d: dict[str, Any]) -> int:
    """1 or 2: the number of axes a plan's fields describe (``axes``, else the shape of its numbers)."""
    axes = d.get("axes")
    if isinstance(axes, (list, tuple)) and len(axes) in (1, 2):
        return len(axes)
    targets = d.get("targets_mm")
    if targets is not None and _is_pair(targets) and len(targets) and _is_pair(targets[0]):
        return 2
    return 2 if _is_pair(d.get("start_mm")) else 1


@dataclass(frozen=True)
class Plan:
    """A capture plan on ``len(axes)`` axes; lengths in mm.

    Construct a one-axis plan with numbers, a two-axis one with pairs (or
    :meth:`xy`, which has the two-axis defaults); ``axes`` follows from them.
    """

    start_mm: float | tuple[float, float] = 0.0
    stop_mm: float | tuple[float, float] = 10.0
    step_mm: float | tuple[float, float] = 1.0
    targets_mm: tuple[float, ...] | tuple[tuple[float, float], ...] | None = None
    directions: str = "+"
    runs: int = 1
    overshoot_mm: float = 1.0
    settle_s: float = 0.2
    frames_per_stop: int = 1
    feed_mm_min: float = 600.0
    pattern: str = "serpentine"  # two axes: the grid's order
    axes: tuple[str, ...] | None = None  # ("X",) or ("X", "Y"); None: from the shape of the fields
    segments: tuple[tuple[float, float], ...] | None = None  # one axis, one board moved: each segment's [first, last] mm

    def __post_init__(self) -> None:
        if self.axes is None:
            d = {"start_mm": self.start_mm, "targets_mm": self.targets_mm}
            object.__setattr__(self, "axes", ("X",) if _axes_of(d) == 1 else ("X", "Y"))
        else:
            object.__setattr__(self, "axes", tuple(str(a) for a in self.axes))
        if len(self.axes) not in (1, 2):
            raise InputError(f"plan: axes must be one or two axis names, got {list(self.axes)}")
        if self.planar:
            self._check_planar()
            return
        if self.directions not in DIRECTIONS:
            raise InputError(f"plan: directions must be one of {DIRECTIONS}, got {self.directions!r}")
        check_plan_fields(self)  # counts and ranges before anything is built from them
        if self.segments is not None:
            from lps_gui.core.planning.segments import check_segments

            object.__setattr__(self, "segments", check_segments(self.segments, self.targets()))

    def _check_planar(self) -> None:
        if self.directions not in DIRECTIONS:
            raise InputError(f"planar plan: directions must be one of {DIRECTIONS}, got {self.directions!r}")
        if self.pattern not in PATTERNS:
            raise InputError(f"planar plan: pattern must be one of {PATTERNS}, got {self.pattern!r}")
        if self.runs < 1 or self.frames_per_stop < 1:
            raise InputError("planar plan: runs and frames_per_stop must be at least 1")
        if not (self.overshoot_mm >= 0 and self.settle_s >= 0 and self.feed_mm_min > 0):
            raise InputError("planar plan: overshoot and settle must be >= 0 and the feed > 0")
        if self.targets_mm is None:
            counts = []
            for a, (s0, s1, ds) in enumerate(zip(self.start_mm, self.stop_mm, self.step_mm)):  # type: ignore[arg-type]
                if not (np.isfinite(ds) and ds > 0) and s1 != s0:
                    raise InputError(f"planar plan: step {ds} mm on axis {self.axes[a]} must be positive")
                counts.append(1 if s1 == s0 else int(round(abs(s1 - s0) / ds)) + 1)
            if counts[0] * counts[1] > MAX_PLANAR_TARGETS:
                raise InputError(f"planar plan: {counts[0]} x {counts[1]} targets exceed the limit of "
                                 f"{MAX_PLANAR_TARGETS}; use a coarser step")
            if counts[0] * counts[1] < 3:
                raise InputError("planar plan: the grid has fewer than 3 targets; widen it or refine the step")
        elif len(self.targets_mm) < 3:
            raise InputError("planar plan: give at least 3 targets [x, y] not on one line")

    @classmethod
    def xy(cls, **fields: Any) -> "Plan":
        """A two-axis plan (SPEC 10); fields not given take the XY defaults (a 10 x 10 mm grid at 5 mm)."""
        fields.setdefault("axes", ("X", "Y"))
        for key, value in (("start_mm", (0.0, 0.0)), ("stop_mm", (10.0, 10.0)), ("step_mm", (5.0, 5.0))):
            fields.setdefault(key, value)
        return cls(**fields)

    @property
    def n_axes(self) -> int:
        """D: 1 on a linear stage, 2 on an XY gantry."""
        return len(self.axes)  # type: ignore[arg-type]

    @property
    def planar(self) -> bool:
        return self.n_axes == 2

    def targets(self) -> np.ndarray:
        """Targets of one forward pass in visiting order (mm): shape (m,) on one axis (ascending), (m, 2) on two."""
        if not self.planar:
            if self.targets_mm is not None:
                return np.sort(np.asarray(self.targets_mm, dtype=float))
            n = int(round((self.stop_mm - self.start_mm) / self.step_mm)) + 1  # type: ignore[operator]
            return np.sort(self.start_mm + self.step_mm * np.arange(n))  # type: ignore[operator]
        if self.targets_mm is not None:
            return np.asarray(self.targets_mm, dtype=float).reshape(-1, 2)
        axes = []
        for s0, s1, ds in zip(self.start_mm, self.stop_mm, self.step_mm):  # type: ignore[arg-type]
            n = 1 if s1 == s0 else int(round(abs(s1 - s0) / ds)) + 1
            axes.append(s0 + np.sign(s1 - s0) * ds * np.arange(n) if n > 1 else np.array([s0]))
        xs, ys = axes
        rows = []
        for j, y in enumerate(ys):
            row = xs if (self.pattern == "raster" or j % 2 == 0) else xs[::-1]
            rows.append(np.column_stack([row, np.full(row.size, y)]))
        return np.concatenate(rows)

    def run_directions(self) -> list[str]:
        return run_directions(self.directions)

    def stops(self) -> Iterator[PlannedStop]:
        """Every frame of the session in capture order (a stitched plan: every segment's runs in turn)."""
        index = 0
        for segment, forward in self._segment_targets():
            for run in range(1, self.runs + 1):
                for direction in self.run_directions():
                    ordered = forward if direction == "+" else forward[::-1]
                    sides = approach_directions(ordered.reshape(len(ordered), self.n_axes), 1 if direction == "+" else -1)
                    for target, side in zip(ordered, sides):
                        where = (float(target[0]), float(target[1])) if self.planar else float(target)
                        approach = tuple(int(s) for s in side)
                        for frame in range(self.frames_per_stop):
                            yield PlannedStop(index, run, direction, where, frame, approach, segment)
                            index += 1

    def _segment_targets(self) -> list[tuple[int | None, np.ndarray]]:
        """(segment, its forward targets): the whole plan as one, or each segment of a stitched plan."""
        forward = self.targets()
        if self.segments is None:
            return [(None, forward)]
        return [(k, forward[(forward >= a - MOVE_TOL_MM) & (forward <= b + MOVE_TOL_MM)])
                for k, (a, b) in enumerate(self.segments)]

    def n_frames(self) -> int:
        visits = sum(len(t) for _, t in self._segment_targets())
        return visits * len(self.run_directions()) * self.runs * self.frames_per_stop

    def arrival_indices(self) -> dict[int, tuple[int, ...]]:
        """Per frame, for each axis, the first frame of the pass since which that axis has held its target.

        An axis that does not move between stops stays where it arrived: the
        simulated gantry keys each axis' repeatability draw on this index, so
        a resumed capture (which re-approaches every axis) reproduces it.
        """
        out: dict[int, tuple[int, ...]] = {}
        first = [0] * self.n_axes
        prev: PlannedStop | None = None
        for s in self.stops():
            here, there = np.atleast_1d(s.target_mm), None if prev is None else np.atleast_1d(prev.target_mm)
            for a in range(self.n_axes):
                same_pass = prev is not None and (prev.run, prev.direction) == (s.run, s.direction)
                if not (same_pass and abs(there[a] - here[a]) <= MOVE_TOL_MM  # type: ignore[index]
                        and prev.approach[a] == s.approach[a]):  # type: ignore[union-attr]
                    first[a] = s.index
            out[s.index] = tuple(first)
            prev = s
        return out

    def approach_start_mm(self, direction: str, first_target_mm: float) -> float:
        """One axis: where to go before a run's first target so it is approached from ``direction``."""
        return first_target_mm - self.overshoot_mm if direction == "+" else first_target_mm + self.overshoot_mm

    def to_dict(self) -> dict[str, Any]:
        """session.json's ``plan``: SPEC 7's fields on one axis, SPEC 10's (with ``axes``) on two."""
        if not self.planar:
            d = {k: getattr(self, k) for k in LINE_FIELDS}
            if d["targets_mm"] is not None:
                d["targets_mm"] = list(d["targets_mm"])
            if self.segments is not None:  # a stitched plan only: every other plan keeps its fields byte for byte
                d["segments"] = [list(seg) for seg in self.segments]
            return d
        d = {
            "axes": list(self.axes), "pattern": self.pattern, "directions": self.directions,  # type: ignore[arg-type]
            "runs": self.runs, "overshoot_mm": self.overshoot_mm, "settle_s": self.settle_s,
            "frames_per_stop": self.frames_per_stop, "feed_mm_min": self.feed_mm_min,
        }
        if self.targets_mm is not None:
            d["targets_mm"] = [list(t) for t in self.targets_mm]  # type: ignore[arg-type]
        else:
            d.update(start_mm=list(self.start_mm), stop_mm=list(self.stop_mm),  # type: ignore[arg-type]
                     step_mm=list(self.step_mm))  # type: ignore[arg-type]
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Plan":
        """The plan of session.json (or a plan file); two axes when ``axes`` has two names or the numbers are pairs."""
        if _axes_of(d) == 2:
            return cls._planar_from_dict(d)
        known = {k: v for k, v in d.items() if k in LINE_FIELDS + ("segments",)}
        if known.get("segments") is not None:
            from lps_gui.core.planning.segments import segments_from_list

            known["segments"] = segments_from_list(known["segments"])
        if known.get("targets_mm") is not None:
            if not isinstance(known["targets_mm"], (list, tuple)):
                raise InputError(f"plan: targets_mm must be a list of positions (mm), not {known['targets_mm']!r}")
            known["targets_mm"] = tuple(known["targets_mm"])
        try:
            return cls(**known, axes=("X",))
        except TypeError as exc:
            raise InputError(f"plan: {exc}; see SPEC section 7 for the plan fields") from exc

    @classmethod
    def _planar_from_dict(cls, d: dict[str, Any]) -> "Plan":
        kw: dict[str, Any] = {}
        for key in ("start_mm", "stop_mm", "step_mm"):
            if key in d:
                kw[key] = _pair(d[key], key)
        if d.get("targets_mm") is not None:
            t = d["targets_mm"]
            if not isinstance(t, (list, tuple)):
                raise InputError("planar plan: targets_mm must be a list of [x, y]")
            kw["targets_mm"] = tuple(_pair(p, f"targets_mm[{i}]") for i, p in enumerate(t))
        for key, typ in (("pattern", str), ("directions", str), ("runs", int), ("overshoot_mm", float),
                         ("settle_s", float), ("frames_per_stop", int), ("feed_mm_min", float)):
            if key in d:
                try:
                    kw[key] = typ(d[key])
                except (TypeError, ValueError):
                    raise InputError(f"planar plan: {key} must be a {typ.__name__}, got {d[key]!r}") from None
        if "axes" in d:
            kw["axes"] = tuple(str(a) for a in d["axes"])
        return cls.xy(**kw)


def approach_directions(ordered: np.ndarray, default_sign: int) -> np.ndarray:
    """Per-axis approach side (+1/-1) of each target visited in ``ordered`` (m, D), shape (m, D).

    An axis keeps the side of the move that brought it to a target. Where it
    did not move on the way in but leaves in the other direction (the start of
    a serpentine row), the engine overshoots first, so the target is approached
    from the side the axis goes on in. Where it reverses right at a target, the
    target belongs to the longer of the two monotonic runs of moves (a line
    beats the jump to the next line; a tie keeps the way in). An axis that
    never moves takes ``default_sign``. On one axis visited in order every
    target takes the pass' own side.
    """
    t = np.asarray(ordered, dtype=float)
    m = t.shape[0]
    out = np.full(t.shape, int(default_sign), dtype=int)
    for a in range(t.shape[1]):
        moves = np.diff(t[:, a])
        sign = np.where(np.abs(moves) > MOVE_TOL_MM, np.sign(moves), 0).astype(int)
        nz = np.flatnonzero(sign)
        if nz.size == 0:
            continue
        if np.all(sign[nz] == sign[nz[0]]):  # monotonic: one side throughout (every one-axis pass)
            out[:, a] = sign[nz[0]]
            continue
        seg = np.concatenate([[0], np.cumsum(sign[nz][1:] != sign[nz][:-1])])  # run id of each move
        seg_len = np.bincount(seg)
        for i in range(m):
            k = int(np.searchsorted(nz, i))  # first nonzero move leaving at or after stop i
            if k == 0:
                out[i, a] = sign[nz[0]]
                continue
            if k == nz.size:
                out[i, a] = sign[nz[-1]]
                continue
            j_in, j_out = nz[k - 1], nz[k]
            s_in, s_out = sign[j_in], sign[j_out]
            lands, leaves = j_in == i - 1, j_out == i
            if s_in == s_out or (lands and not leaves) or (not lands and not leaves):
                out[i, a] = s_in
            elif leaves and not lands:
                out[i, a] = s_out
            else:
                out[i, a] = s_out if seg_len[seg[k]] > seg_len[seg[k - 1]] else s_in
    return out


def iso_lines_plan(
    x_targets_mm: np.ndarray,
    y_levels_mm: np.ndarray,
    y_targets_mm: np.ndarray,
    x_levels_mm: np.ndarray,
    runs: int = 5,
    **kw: Any,
) -> Plan:
    """ISO 230-2 lines per axis of a gantry: along X at each Y level, then along Y at each X level.

    With ``directions="both"`` (the default here) each line is run forward
    and backward, ``runs`` times (ISO 230-2 asks for 5).
    """
    targets: list[tuple[float, float]] = []
    for y in np.atleast_1d(y_levels_mm):
        targets += [(float(x), float(y)) for x in np.sort(np.atleast_1d(x_targets_mm))]
    for x in np.atleast_1d(x_levels_mm):
        targets += [(float(x), float(y)) for y in np.sort(np.atleast_1d(y_targets_mm))]
    kw.setdefault("directions", "both")
    return Plan.xy(targets_mm=tuple(targets), runs=runs, **kw)


def iso_lines_on_grid(grid: Plan, levels: int = 3, runs: int = 5) -> Plan:
    """The ISO 230-2 lines preset on a two-axis ``grid``: every grid X along Y at ``levels`` Y levels (both
    ends and between), every grid Y along X at ``levels`` X levels; forward and backward, ``runs`` runs.

    The grid's overshoot, settle, frames per stop and feed are kept.
    """
    t = grid.targets()
    xs, ys = np.unique(t[:, 0]), np.unique(t[:, 1])

    def pick(v: np.ndarray) -> np.ndarray:
        return np.unique(v[np.round(np.linspace(0, v.size - 1, levels)).astype(int)])

    keep = {k: getattr(grid, k) for k in ("overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min")}
    return iso_lines_plan(xs, pick(ys), ys, pick(xs), runs=runs, **keep)
