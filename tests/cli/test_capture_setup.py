"""`lps capture --spec/--iso-plan/--board-temp/--operator ...` write what the report needs into session.json."""
import json

import numpy as np
import pytest

from lps_gui.cli import main
from lps_gui.core.planning.presets import SPEC_PRESETS, iso230_targets, parse_spec
from lps_gui.errors import InputError


def test_capture_writes_spec_environment_identification_and_iso_plan(tmp_path, capsys):
    out = tmp_path / "s"
    rc = main(["capture", "--out", str(out), "--start", "0", "--stop", "20", "--iso-plan", "--iso-targets", "5",
               "--pitch", "5", "--spec", "paper", "--board-temp", "23", "--board-cte", "23", "--square-u", "0.2",
               "--env-notes", "probe on the board", "--operator", "A. Meier", "--serial", "SN-7"])
    assert rc == 0, capsys.readouterr().err
    meta = json.loads((out / "session.json").read_text())
    assert meta["stage_spec"] == SPEC_PRESETS["paper"] == {"accuracy_um": 20.0, "repeatability_um": 5.0,
                                                           "straightness_um": 38.0}
    assert meta["environment"] == {"board_temperature_c": 23.0, "board_cte_ppm_per_k": 23.0,
                                   "square_mm_uncertainty_um": 0.2, "notes": "probe on the board"}
    assert meta["identification"] == {"operator": "A. Meier", "stage_serial": "SN-7"}
    plan = meta["plan"]
    assert plan["runs"] == 5 and plan["directions"] == "both" and len(plan["targets_mm"]) == 5


def test_bad_spec_fails_in_one_line_before_anything_is_written(tmp_path, capsys):
    rc = main(["capture", "--out", str(tmp_path / "s"), "--start", "0", "--stop", "4", "--step", "2",
               "--spec", "accuracy=fast"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "--spec" in err
    assert not (tmp_path / "s").exists()


def test_parse_spec_presets_and_pairs():
    assert parse_spec("accuracy=10,repeatability=2") == {"accuracy_um": 10.0, "repeatability_um": 2.0}
    for bad in ("", "speed=3", "accuracy=-1"):
        with pytest.raises(InputError):
            parse_spec(bad)


def test_iso_targets_cover_the_pitch_phase_and_keep_the_ends():
    t = np.array(iso230_targets(0.0, 100.0, 21, pitch_mm=5.0))
    assert t[0] == 0.0 and t[-1] == 100.0 and np.all(np.diff(t) > 0)
    phase = np.sort(np.mod(t[1:-1], 5.0))
    assert np.max(np.diff(phase)) < 1.0 and phase[0] < 0.5 and phase[-1] > 4.0  # no gap: the pitch is sampled
    uniform = np.mod(np.linspace(0, 100, 21), 5.0)
    assert np.ptp(uniform) == 0  # what the preset avoids: every uniform target at the same phase
