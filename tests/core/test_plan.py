"""One plan type for one or two axes: a one-axis plan is a grid with one axis.

The expected stops and dicts below are what the separate line plan and planar
plan of before the merge gave (recorded from that code), so session.json and
captures.jsonl stay as they were, byte for byte.
"""
from __future__ import annotations

import json

import pytest

from lps_gui.core.planning.plan import Plan, PlannedStop
from lps_gui.errors import InputError

# Plan(0, 4, 2, directions="both", runs=2).stops() before the merge: (index, run, direction, target, frame)
LINE_STOPS = [(0, 1, "+", 0.0, 0), (1, 1, "+", 2.0, 0), (2, 1, "+", 4.0, 0), (3, 1, "-", 4.0, 0), (4, 1, "-", 2.0, 0),
              (5, 1, "-", 0.0, 0), (6, 2, "+", 0.0, 0), (7, 2, "+", 2.0, 0), (8, 2, "+", 4.0, 0), (9, 2, "-", 4.0, 0),
              (10, 2, "-", 2.0, 0), (11, 2, "-", 0.0, 0)]


def test_a_one_axis_plan_has_the_line_plans_stops_with_its_own_approach_side():
    plan = Plan(start_mm=0.0, stop_mm=4.0, step_mm=2.0, directions="both", runs=2)
    stops = list(plan.stops())
    assert plan.axes == ("X",) and not plan.planar and plan.n_axes == 1
    assert [tuple(s)[:5] for s in stops] == LINE_STOPS
    assert all(isinstance(s.target_mm, float) for s in stops)  # captures.jsonl keeps a scalar target_mm
    assert [s.approach for s in stops] == [(1,) if s.direction == "+" else (-1,) for s in stops]
    assert plan.n_frames() == len(stops)


def test_explicit_one_axis_targets_are_sorted_and_frames_repeat_a_stop():
    plan = Plan(targets_mm=(5.0, 1.0, 3.0), directions="-", frames_per_stop=2)
    assert [tuple(s)[:5] for s in plan.stops()] == [(0, 1, "-", 5.0, 0), (1, 1, "-", 5.0, 1), (2, 1, "-", 3.0, 0),
                                                    (3, 1, "-", 3.0, 1), (4, 1, "-", 1.0, 0), (5, 1, "-", 1.0, 1)]


def test_a_one_axis_plan_is_the_x_row_of_a_grid_held_in_y():
    line = Plan(start_mm=0.0, stop_mm=20.0, step_mm=10.0, directions="both", runs=2)
    grid = Plan.xy(start_mm=(0.0, 5.0), stop_mm=(20.0, 5.0), step_mm=(10.0, 1.0), directions="both", runs=2)
    assert grid.planar and grid.axes == ("X", "Y")
    for a, b in zip(line.stops(), grid.stops(), strict=True):
        assert (a.index, a.run, a.direction, a.frame) == (b.index, b.run, b.direction, b.frame)
        assert a.target_mm == b.target_mm[0] and b.target_mm[1] == 5.0
        assert a.approach == b.approach[:1]  # X's side; the held Y keeps the pass' side
    assert [arr[0] for arr in line.arrival_indices().values()] == [s.index for s in line.stops()]  # X moves every stop


def test_session_json_plan_dicts_are_those_of_before():
    line = Plan(start_mm=0.0, stop_mm=4.0, step_mm=2.0, directions="both", runs=2)
    assert json.dumps(line.to_dict()) == (
        '{"start_mm": 0.0, "stop_mm": 4.0, "step_mm": 2.0, "targets_mm": null, "directions": "both", "runs": 2, '
        '"overshoot_mm": 1.0, "settle_s": 0.2, "frames_per_stop": 1, "feed_mm_min": 600.0}')
    explicit = Plan(targets_mm=(5.0, 1.0, 3.0), directions="-", frames_per_stop=2)
    assert json.dumps(explicit.to_dict()) == (
        '{"start_mm": 0.0, "stop_mm": 10.0, "step_mm": 1.0, "targets_mm": [5.0, 1.0, 3.0], "directions": "-", '
        '"runs": 1, "overshoot_mm": 1.0, "settle_s": 0.2, "frames_per_stop": 2, "feed_mm_min": 600.0}')
    as_read = Plan.from_dict({"start_mm": 0, "stop_mm": 10, "step_mm": 5})  # integers stay integers
    assert json.dumps(as_read.to_dict()).startswith('{"start_mm": 0, "stop_mm": 10, "step_mm": 5, "targets_mm": null')
    grid = Plan.xy(start_mm=(0, 0), stop_mm=(20, 10), step_mm=(10, 10), directions="both")
    assert json.dumps(grid.to_dict()) == (
        '{"axes": ["X", "Y"], "pattern": "serpentine", "directions": "both", "runs": 1, "overshoot_mm": 1.0, '
        '"settle_s": 0.2, "frames_per_stop": 1, "feed_mm_min": 600.0, "start_mm": [0, 0], "stop_mm": [20, 10], '
        '"step_mm": [10, 10]}')
    listed = Plan.xy(targets_mm=((0, 0), (5, 0), (0, 5)))
    assert json.dumps(listed.to_dict()) == (
        '{"axes": ["X", "Y"], "pattern": "serpentine", "directions": "+", "runs": 1, "overshoot_mm": 1.0, '
        '"settle_s": 0.2, "frames_per_stop": 1, "feed_mm_min": 600.0, "targets_mm": [[0, 0], [5, 0], [0, 5]]}')


@pytest.mark.parametrize("d, axes", [
    ({"start_mm": 0.0, "stop_mm": 4.0, "step_mm": 2.0}, ("X",)),
    ({"axes": ["X", "Y"], "start_mm": [0, 0], "stop_mm": [20, 10], "step_mm": [10, 10]}, ("X", "Y")),
    ({"targets_mm": [[0, 0], [5, 0], [0, 5]]}, ("X", "Y")),  # pairs of numbers: two axes
    ({"targets_mm": [0, 5, 10]}, ("X",)),
])
def test_from_dict_reads_the_axes_from_the_fields(d, axes):
    plan = Plan.from_dict(d)
    assert plan.axes == axes
    assert Plan.from_dict(plan.to_dict()) == plan


def test_the_number_of_axes_follows_the_fields_and_must_be_one_or_two():
    assert Plan(start_mm=(0.0, 0.0), stop_mm=(10.0, 10.0), step_mm=(5.0, 5.0)).planar
    assert Plan(targets_mm=((0.0, 0.0), (1.0, 0.0), (0.0, 1.0))).planar
    with pytest.raises(InputError, match="one or two axis"):
        Plan(axes=("X", "Y", "Z"))
    with pytest.raises(InputError, match="plan: step"):  # one-axis limits (SPEC 7) stay those of the line plan
        Plan(start_mm=0.0, stop_mm=10.0, step_mm=-1.0)


def test_planned_stop_of_one_axis_without_approach_still_constructs():
    stop = PlannedStop(0, 1, "+", 2.0, 0)
    assert stop.approach == () and stop.target_mm == 2.0
