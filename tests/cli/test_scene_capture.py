"""`lps capture --scene`: a measured session's first pass again, the board replaced by the light-field scene."""

import numpy as np

from lps_gui.cli import main as lps_main
from lps_gui.io.session import Session


def _measured(tmp_path, directions="both"):
    m = tmp_path / "m"
    assert lps_main(["simulate", str(m), "--points", "--preset", "small", "--stops", "6", "--directions", directions]) == 0
    assert lps_main(["estimate", str(m)]) == 0
    return m


def test_a_scene_capture_repeats_the_first_pass_and_names_its_measurement(tmp_path, capsys):
    m = _measured(tmp_path)
    s = tmp_path / "scene"
    assert lps_main(["capture", "--scene", str(m), "--out", str(s)]) == 0
    scene = Session.open(s)
    measured = Session.open(m)
    link = scene.meta["scene"]["measurement_session"]
    assert link["path"] == str(m.resolve())
    assert len(link["results_sha256"]) == 64
    assert scene.plan().directions == "+" and scene.plan().runs == 1
    records = scene.records()
    forward = [r for r in measured.records() if r.direction == "+" and r.run == 1]
    assert [r.target_mm for r in records] == [r.target_mm for r in forward]
    assert "scene" in scene.truth and len(scene.truth["axis_mm"]) == len(records)
    # a new visit of every stop: the repeatability draws are the scene's own, not the measurement's
    m_axis = np.array(measured.truth["axis_mm"])[[r.index for r in forward]]
    assert not np.allclose(np.array(scene.truth["axis_mm"]), m_axis, atol=1e-7, rtol=0)
    assert (s / records[0].file).stat().st_size > 10_000  # a textured scene, not an empty frame


def test_a_scene_capture_refuses_a_measurement_without_results_and_a_plan_of_its_own(tmp_path, capsys):
    m = tmp_path / "m"
    assert lps_main(["simulate", str(m), "--points", "--preset", "small", "--stops", "6"]) == 0
    assert lps_main(["capture", "--scene", str(m), "--out", str(tmp_path / "s")]) != 0
    assert "no results.json; estimate the measurement first" in capsys.readouterr().err
    assert not (tmp_path / "s" / "session.json").exists()
    assert lps_main(["estimate", str(m)]) == 0
    assert lps_main(["capture", "--scene", str(m), "--step", "2", "--out", str(tmp_path / "s2")]) != 0
    assert "--step: a scene capture repeats the measured session's plan" in capsys.readouterr().err


def test_lps_lightfield_refuses_a_session_that_is_not_a_scene_and_a_lost_measurement(tmp_path, capsys):
    m = _measured(tmp_path, "+")
    assert lps_main(["lightfield", str(m), "--out", str(tmp_path / "lf")]) != 0
    assert "not a scene session" in capsys.readouterr().err
    s = tmp_path / "scene"
    assert lps_main(["capture", "--scene", str(m), "--out", str(s)]) == 0
    m.rename(tmp_path / "moved")
    assert lps_main(["lightfield", str(s), "--out", str(tmp_path / "lf")]) != 0
    assert "its measurement session" in capsys.readouterr().err
    assert lps_main(["lightfield", str(s), "--measurement", str(tmp_path / "moved"), "--out", str(tmp_path / "lf")]) == 0
    assert (tmp_path / "lf" / "lightfield.json").is_file()
