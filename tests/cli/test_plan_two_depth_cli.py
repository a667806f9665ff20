"""`lps plan-rig --two-depth`: a far and a near row for the paper's camera, and the angular sigmas per stop."""
from __future__ import annotations

import json

from lps_gui.cli import main as lps_main
PAPER_CAMERA = ["--focal-mm", "8", "--pixel-um", "3.45", "--image", "1920x1080"]


def test_two_depth_proposes_smaller_near_targets_and_predicts_the_angles(capsys):
    rc = lps_main(["plan-rig", *PAPER_CAMERA, "--travel", "600", "--step", "10", "--distance-mm", "800",
                   "--two-depth", "300", "--json"])
    [plan] = json.loads(capsys.readouterr().out)
    assert rc == 0 and plan["stops"] == 61
    assert plan["far"]["square_mm"] == 30.0 and plan["near"]["square_mm"] == 15.0  # SPEC 14's layout
    assert plan["far"]["inner_corners"] == plan["near"]["inner_corners"] == [10, 7]
    sig, one = plan["angle_sigma_urad"], plan["single_view_urad"]
    assert list(sig) == ["EAX", "EBX", "ECX"]
    assert all(one[k] <= sig[k] < 1.2 * one[k] for k in sig) and all(v < 15.0 for v in sig.values())
    far, near = plan["make_targets"]
    assert "--prefix F" in far and f"--first-marker {plan['far']['count'] * 44} --prefix N" in near


def test_two_depth_table_and_its_errors(capsys):
    rc = lps_main(["plan-rig", *PAPER_CAMERA, "--travel", "600", "--step", "20", "--distance-mm", "800",
                   "--two-depth", "300"])
    out = capsys.readouterr().out
    assert rc == 0 and "EAX / EBX / ECX" in out and "print them: lps make-targets near" in out
    for args, words in ((["--travel", "600", "--two-depth", "300"], "--distance-mm"),
                        (["--travel", "600", "--distance-mm", "800", "--two-depth", "900"], "between the camera")):
        rc = lps_main(["plan-rig", *PAPER_CAMERA, *args])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and words in err[0]
