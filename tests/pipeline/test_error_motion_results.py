"""SPEC 14 through `lps estimate`: error motions in results.json and positions.csv, against the simulator's truth."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel
from lps_gui.errors import InputError
from lps_gui.io.results.document import POSITION_COLUMNS, positions_csv
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.pipeline.results.error_motions import tool_point
from lps_gui.sim.points import simulate_point_session


def _board_session(folder, tool_point=None):
    """The paper's rig (one 30x18 board at 600 mm) over 150 mm; yaw 150 urad, roll and pitch 100 urad."""
    errors = StageErrorModel(scale_ppm=20.0, repeatability_um=0.5,
                             roll_urad=ErrorProfile(amplitude=100.0, period_mm=150.0),
                             pitch_urad=ErrorProfile(poly=(0.0, 600.0)),
                             yaw_urad=ErrorProfile(amplitude=150.0, period_mm=300.0), angle_noise_urad=3.0)
    spec = paper_rig_spec(seed=5, errors=errors, plan=Plan(start_mm=0.0, stop_mm=150.0, step_mm=1.5))
    session = simulate_point_session(spec, folder)
    if tool_point is not None:
        session.meta["tool_point"] = tool_point
        session.save_meta()
    return folder


def test_one_board_resolves_the_rotation_about_the_view_and_not_the_tilts(tmp_path):
    results = estimate_session(_board_session(tmp_path / "s"))
    em = results["error_motions"]
    assert em["resolved"] == {"EXX": False, "EYX": False, "EZX": False, "EAX": False, "EBX": False, "ECX": True}
    assert list(em["motions"]) == ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX"]
    truth = em["truth"]["ECX"]
    assert 0.5 < truth["z_mean_square"] < 2.0
    assert truth["rms_error_urad"] < 1.3 * em["motions"]["ECX"]["median_centred_sigma"]
    rows = (tmp_path / "s" / "positions.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert header[-6:] == ["eax_urad", "ebx_urad", "ecx_urad", "eax_sigma_urad", "ebx_sigma_urad", "ecx_sigma_urad"]
    cells = [r.split(",") for r in rows[1:]]
    assert all(c[-6] == c[-5] == c[-3] == c[-2] == "" for c in cells)  # the tilts: empty, not resolved
    assert cells[0][-4] == "0" and all(c[-4] and c[-1] for c in cells[1:])
    # a single board's SPEC 7 columns stay as they were: the table without error_motions is the same bytes
    older = {k: v for k, v in results.items() if k != "error_motions"}
    before = [",".join(r.split(",")[: len(POSITION_COLUMNS)]) for r in rows]
    assert "\n".join(before) + "\n" == positions_csv(json.loads(json.dumps(older)))


def test_the_tool_point_turns_pitch_and_yaw_into_positioning_error(tmp_path):
    folder = _board_session(tmp_path / "s", {"offset_mm": [0.0, 80.0, 120.0], "frame": "stage"})
    results = estimate_session(folder)
    tp = results["error_motions"]["tool_point"]
    assert tp["offset_mm"] == [0.0, 80.0, 120.0] and tp["frame"] == "stage"
    abbe = np.array(tp["abbe_um"], dtype=float)
    # first order: the tool's X moves by yaw x (its Y offset) - pitch x (its Z offset), relative to the first stop
    em = results["error_motions"]["motions"]
    pitch = np.array(em["EBX"]["values"], float) * 1e-6
    yaw = np.array(em["ECX"]["values"], float) * 1e-6
    assert np.allclose(abbe, 1e3 * (-yaw * 80.0 + pitch * 120.0), atol=0.05)


@pytest.mark.parametrize("bad", [{"offset_mm": [0, 1]}, {"offset_mm": [0, 1, "2"]}, {"offset_mm": [0, 0, 0], "frame": "x"},
                                 [1, 2, 3], {"offset_mm": [0, float("nan"), 0]}])
def test_a_bad_tool_point_is_a_one_line_error(bad):
    with pytest.raises(InputError, match="tool_point must be") as err:
        tool_point({"tool_point": bad}, "s/session.json")
    assert "\n" not in str(err.value) and str(err.value).startswith("s/session.json: ")


def test_a_bad_tool_point_stops_lps_estimate_before_anything_is_written(tmp_path):
    folder = _board_session(tmp_path / "s", {"offset_mm": [0, 1]})
    with pytest.raises(InputError, match="tool_point must be"):
        estimate_session(folder)
    assert not (folder / "results.json").exists()
