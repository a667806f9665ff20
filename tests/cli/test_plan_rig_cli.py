"""`lps plan-rig`: the planning aid from the shell."""
from __future__ import annotations

import json

from lps_gui.cli import main as lps_main
CAMERA = ["--focal-mm", "8.18", "--pixel-um", "5.86", "--image", "1920x1080", "--inner-corners", "30x18",
          "--square-mm", "10"]


def test_planar_table_over_distances(capsys):
    rc = lps_main(["plan-rig", *CAMERA, "--distance-mm", "300,600", "--stop", "140,80", "--step", "10"])
    out = capsys.readouterr().out
    assert rc == 3  # the board leaves the view at 300 mm
    assert "135 targets on X,Y" in out and "no (" in out and "move the camera back" in out


def test_line_plan_as_json(capsys):
    rc = lps_main(["plan-rig", *CAMERA, "--distance-mm", "600", "--stop", "399", "--step", "1", "--json"])
    rows = json.loads(capsys.readouterr().out)
    assert rc == 0 and rows[0]["axes"] == ["X"] and rows[0]["board_in_view"]
    assert 2.0 < rows[0]["sigma_um_median"] < 3.5


def test_missing_camera_is_a_one_line_error(capsys):
    rc = lps_main(["plan-rig", "--inner-corners", "9x6", "--square-mm", "20", "--distance-mm", "500",
                   "--stop", "50", "--step", "5"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--focal-mm" in err[0]


PAPER_CAMERA = ["--focal-mm", "8", "--pixel-um", "3.45", "--image", "1920x1080"]


def test_one_board_over_the_paper_travel_says_it_leaves_the_view_and_suggests_a_row(capsys):
    rc = lps_main(["plan-rig", *PAPER_CAMERA, "--inner-corners", "9x6", "--square-mm", "25", "--distance-mm", "1000",
                   "--stop", "1524", "--step", "12.7"])
    captured = capsys.readouterr()
    notes = [line for line in captured.out.splitlines() if "leaves the view" in line]
    assert rc == 3 and not captured.err and len(notes) == 1
    assert "lps plan-rig --travel 1524" in notes[0] and "singular" not in captured.out


def test_travel_proposes_a_row_for_the_wanted_sigma(capsys):
    rc = lps_main(["plan-rig", *PAPER_CAMERA, "--travel", "1524", "--sigma-um", "6", "--json"])
    [plan] = json.loads(capsys.readouterr().out)
    assert rc == 0 and plan["sigma_um_median"] <= 6.0 and plan["n_targets"] >= 3 and plan["stops"] == 121
    assert plan["make_targets"].startswith(f"lps make-targets row --count {plan['n_targets']}")


def test_travel_without_sigma_or_distance_is_a_one_line_error(capsys):
    rc = lps_main(["plan-rig", *PAPER_CAMERA, "--travel", "1524"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--sigma-um" in err[0]
