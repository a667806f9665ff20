"""`lps compensate --error-motions`: the six error motions per nominal position, against the simulator's truth."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.errors import InputError
from lps_gui.pipeline.compensate import compensate_session
from lps_gui.pipeline.estimate import estimate_session
from tests.pipeline.test_error_motion_results import _board_session


def test_the_table_holds_the_resolved_motions_per_nominal_position(tmp_path, capsys):
    folder = _board_session(tmp_path / "s")
    results = estimate_session(folder)
    out = tmp_path / "em.csv"
    assert lps_main(["compensate", str(folder), "--format", "csv", "--out", str(tmp_path / "c.csv"),
                     "--error-motions", str(out)]) == 0
    assert "error motions per nominal position" in capsys.readouterr().out
    header, *lines = out.read_text().splitlines()
    assert header.split(",") == ["nominal_mm", "exx_um", "exx_sigma_um", "eyx_um", "eyx_sigma_um", "ezx_um",
                                 "ezx_sigma_um", "eax_urad", "eax_sigma_urad", "ebx_urad", "ebx_sigma_urad",
                                 "ecx_urad", "ecx_sigma_urad"]
    cells = [line.split(",") for line in lines]
    nominal = np.array([float(c[0]) for c in cells])
    assert np.allclose(nominal, [r["target_mm"] for r in results["positions"]])  # one capture per target here
    assert all(c[1:11] == [""] * 10 for c in cells)  # one board: only the rotation about the view is resolved
    ecx, sigma = (np.array([float(c[k]) for c in cells]) for k in (11, 12))
    truth = np.array(results["error_motions"]["truth"]["ECX"]["true_values"], float)
    e = ecx - truth
    assert np.all(np.abs(e - e.mean()) < 4.5 * sigma)


def test_results_without_error_motions_are_a_one_line_error_and_nothing_is_written(tmp_path):
    folder = _board_session(tmp_path / "s")
    results = estimate_session(folder)
    del results["error_motions"]
    (folder / "results.json").write_text(json.dumps(results))
    with pytest.raises(InputError, match="no error_motions") as err:
        compensate_session(folder, "csv", tmp_path / "c.csv", error_motions_out=tmp_path / "em.csv")
    assert "\n" not in str(err.value)
    assert not (tmp_path / "c.csv").exists() and not (tmp_path / "em.csv").exists()
