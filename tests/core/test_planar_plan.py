"""Planar plans: grid order, passes, per-axis approach sides, limits."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan, approach_directions, iso_lines_plan
from lps_gui.errors import InputError


def test_serpentine_and_raster_orders():
    s = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10), pattern="serpentine").targets()
    assert s.tolist() == [[0, 0], [10, 0], [20, 0], [20, 10], [10, 10], [0, 10]]
    r = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10), pattern="raster").targets()
    assert r.tolist() == [[0, 0], [10, 0], [20, 0], [0, 10], [10, 10], [20, 10]]


def test_backward_pass_visits_the_grid_in_reverse():
    plan = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10), directions="both", runs=2)
    stops = list(plan.stops())
    assert len(stops) == plan.n_frames() == 24
    fwd = [s.target_mm for s in stops if s.run == 1 and s.direction == "+"]
    bwd = [s.target_mm for s in stops if s.run == 1 and s.direction == "-"]
    assert bwd == fwd[::-1]
    assert [s.index for s in stops] == list(range(24))


def test_serpentine_rows_are_approached_from_their_own_side():
    plan = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10))
    app = [s.approach[0] for s in plan.stops()]
    assert app == [1, 1, 1, -1, -1, -1]  # row 2 starts after an overshoot in x


def test_iso_lines_end_of_line_keeps_its_side():
    ordered = np.array([[0, 0], [10, 0], [20, 0], [0, 10], [10, 10], [20, 10]], float)
    assert approach_directions(ordered, 1)[:, 0].tolist() == [1, 1, 1, 1, 1, 1]
    plan = iso_lines_plan([0, 10, 20], [0, 50], [0, 25, 50], [10], runs=5)
    assert plan.directions == "both" and plan.runs == 5
    assert plan.n_frames() == (6 + 3) * 2 * 5


@pytest.mark.parametrize("kw, match", [
    (dict(step_mm=(0.0, 1.0)), "step"),
    (dict(start_mm=(0, 0), stop_mm=(1e6, 1e6), step_mm=(1.0, 1.0)), "exceed the limit"),
    (dict(pattern="spiral"), "pattern"),
    (dict(targets_mm=((0, 0), (1, 1))), "at least 3"),
    (dict(overshoot_mm=-1.0), "overshoot"),
])
def test_bad_plans_give_one_line_errors(kw, match):
    with pytest.raises(InputError, match=match):
        Plan.xy(**kw)


def test_round_trip_through_dict():
    plan = Plan.xy(start_mm=(0, 5), stop_mm=(30, 25), step_mm=(10, 10), directions="both", runs=3)
    again = Plan.from_dict(plan.to_dict())
    assert again == plan
    t = Plan.xy(targets_mm=((0, 0), (5, 0), (0, 5)))
    assert Plan.from_dict(t.to_dict()).targets().tolist() == [[0, 0], [5, 0], [0, 5]]
    with pytest.raises(InputError, match=r"targets_mm\[1\]"):
        Plan.from_dict({"targets_mm": [[0, 0], [1, "a"], [2, 2]]})


def test_arrival_indices_follow_each_axis():
    plan = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10))
    arr = plan.arrival_indices()
    # row 1: x moves every stop, y holds from stop 0; row 2 starts at stop 3 (y moved there)
    assert [arr[i] for i in range(6)] == [(0, 0), (1, 0), (2, 0), (3, 3), (4, 3), (5, 3)]


def test_axis_moves_overshoot_only_where_an_axis_would_arrive_from_the_wrong_side():
    from lps_gui.capture.moves import axis_moves
    from lps_gui.core.planning.plan import PlannedStop

    stop = PlannedStop(0, 1, "+", (10.0, 5.0), 0, (1, -1))
    sides = [None, None]
    moves = axis_moves((0.0, 0.0), sides, stop, overshoot_mm=1.0)
    # X comes up from 0: straight there; Y must arrive from above: overshoot to 6 first
    assert moves == [("X", 10.0), ("Y", 6.0), ("Y", 5.0)] and sides == [1, -1]
    assert axis_moves((10.0, 5.0), sides, stop, 1.0) == []  # there already, from the right sides
    assert axis_moves((10.0, 5.0), [None, -1], stop, 1.0) == [("X", 9.0), ("X", 10.0)]  # side unknown after a pause
