"""Positions of imported images (SPEC 16): a step as capture's plan, name patterns, a CSV, directions and runs read
from the positions."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.capture.import_positions import infer_passes, plan_of, stops_from_csv, stops_from_names, stops_from_step
from lps_gui.core.planning.plan import Plan
from lps_gui.errors import InputError


def _passes(seq):
    d, r = infer_passes(np.array(seq, dtype=float))
    return "".join(d), r


@pytest.mark.parametrize("seq, dirs, runs", [
    ([0, 1, 2, 3], "++++", [1] * 4),
    ([3, 2, 1, 0], "----", [1] * 4),
    # both ends of a forward-backward sweep listed: the second 3 leaves with the backward pass, as a capture lists it
    ([0, 1, 2, 3, 3, 2, 1, 0], "++++----", [1] * 8),
    ([0, 1, 2, 3, 2, 1, 0], "++++---", [1] * 7),  # one image at the turn: it stays with the arriving pass
    ([0, 0, 1, 1, 2, 2, 2, 2, 1, 1, 0, 0], "++++++------", [1] * 12),  # two frames a stop
    ([0, 1, 2, 2, 1, 0, 0, 1, 2, 2, 1, 0], "+++---+++---", [1] * 6 + [2] * 6),
    ([0, 1, 2, 0, 1, 2, 0, 1, 2], "+" * 9, [1, 1, 1, 2, 2, 2, 3, 3, 3]),  # returns to the start: runs, not passes
])
def test_directions_and_runs_are_read_from_the_positions(seq, dirs, runs):
    assert _passes(seq) == (dirs, runs)


@pytest.mark.parametrize("directions, runs", [("+", 1), ("-", 2), ("both", 2)])
def test_a_step_lists_the_images_as_capture_plans_them(directions, runs):
    plan = Plan(start_mm=5.0, stop_mm=9.0, step_mm=2.0, directions=directions, runs=runs)
    planned = list(plan.stops())
    files = [f"im{i}.png" for i in range(len(planned))]
    stops = stops_from_step(files, 5.0, 2.0, directions, runs)
    assert [(s.file, s.target_mm, s.direction, s.run) for s in stops] == \
        [(f, p.target_mm, p.direction, p.run) for f, p in zip(files, planned)]
    # the same positions without --directions/--runs read back the same passes
    assert [(s.direction, s.run) for s in stops] == list(zip(*infer_passes(np.array([s.target_mm for s in stops]))))


def test_a_step_refuses_images_that_do_not_split_into_the_passes():
    with pytest.raises(InputError, match="7 images do not split into 2 pass"):
        stops_from_step([f"{i}.png" for i in range(7)], 0.0, 1.0, "both", 1)


def test_names_give_positions_in_natural_order():
    files = ["pos_10.png", "pos_2.png", "pos_-1.5.png", "pos_1.25.png", "pos_0,5.png"]
    stops = stops_from_names(files, "pos_{mm}.png")
    assert [s.target_mm for s in stops] == [-1.5, 0.5, 1.25, 2.0, 10.0]  # {mm} compared as a number
    assert [s.file for s in stops] == ["pos_-1.5.png", "pos_0,5.png", "pos_1.25.png", "pos_2.png", "pos_10.png"]
    # a counter before the position orders the images: a sweep there and back
    sweep = stops_from_names(["img9_0.png", "img10_0.5.png", "img11_1.png", "img12_0.5.png", "img13_0.png"], "img*_{mm}.png")
    assert [(s.target_mm, s.direction) for s in sweep] == [(0, "+"), (0.5, "+"), (1, "+"), (0.5, "-"), (0, "-")]


def test_names_with_index_run_and_direction():
    files = ["r2_b_x4.tif", "r1_f_x0.tif", "r1_b_x4.tif", "r1_f_x4.tif", "r1_b_x0.tif", "r2_f_x0.tif"]
    stops = stops_from_names(files, "r{run}_{dir}_x{mm}.tif")
    assert [(s.run, s.direction, s.target_mm) for s in stops] == [
        (1, "+", 0.0), (1, "+", 4.0), (1, "-", 4.0), (1, "-", 0.0), (2, "+", 0.0), (2, "-", 4.0)]
    by_index = stops_from_names(["3-at-1.png", "1-at-0.png", "2-at-2.png"], "{index}-at-{mm}*")
    assert [s.target_mm for s in by_index] == [0.0, 2.0, 1.0]


@pytest.mark.parametrize("pattern, match", [
    ("pos.png", "no {mm} field"),
    ("{mm}_{mm}.png", "appears twice"),
    ("{pos}.png", "unknown field {pos}"),
])
def test_bad_patterns_are_one_line(pattern, match):
    with pytest.raises(InputError, match=match):
        stops_from_names(["1.png"], pattern)


def test_a_name_without_a_number_names_the_file():
    with pytest.raises(InputError, match=r"^photos/pos_x\.png: the name does not match --from-names") as exc:
        stops_from_names(["pos_1.png", "pos_x.png"], "pos_{mm}.png", "photos/")
    assert "\n" not in str(exc.value)


def test_csv_rows_keep_their_order_and_line_numbers():
    text = "file,target,direction,run\na.png,0,+,1\nb.png,2,fwd,1\n\n# a note\nc.png,2,-,1\nd.png,0,-,1\n"
    stops, lines = stops_from_csv(text, "p.csv")
    assert [(s.file, s.target_mm, s.direction, s.run) for s in stops] == [
        ("a.png", 0.0, "+", 1), ("b.png", 2.0, "+", 1), ("c.png", 2.0, "-", 1), ("d.png", 0.0, "-", 1)]
    assert lines == [2, 3, 6, 7]
    inferred, _ = stops_from_csv("a.png,0\nb.png,1\nc.png,1\nd.png,0\n", "p.csv")
    assert "".join(s.direction for s in inferred) == "++--"


@pytest.mark.parametrize("text, match", [
    ("a.png,0\nb.png\n", r"p\.csv: line 2 has 1 fields"),
    ("a.png,0\nb.png,one\n", r"p\.csv: line 2: target 'one' is not a number"),
    ("a.png,0,+,1\nb.png,1\n", r"p\.csv: line 2: give direction and run on every line or on none"),
    ("a.png,0,up,1\n", r"line 1: direction 'up'"),
    ("a.png,0,+,0\n", r"line 1: run '0'"),
    ("a.png,0\nb.png,1\na.png,2\n", r"p\.csv: line 3: a\.png is listed again \(line 1\)"),
    ("file,target\n", r"p\.csv: no rows"),
])
def test_bad_csv_rows_name_the_line(text, match):
    with pytest.raises(InputError, match=match):
        stops_from_csv(text, "p.csv")


def test_the_plan_records_what_was_found():
    stops, _ = stops_from_csv("a,0\nb,1.5\nc,3\nd,3\ne,1.5\nf,0\ng,0\nh,1.5\n", "p.csv")
    plan = plan_of(stops)
    assert plan.targets_mm == (0.0, 1.5, 3.0) and plan.directions == "both" and plan.runs == 2
    with pytest.raises(InputError, match="all 2 images are at 1 mm"):
        plan_of(stops_from_csv("a,1\nb,1\n", "p.csv")[0])
