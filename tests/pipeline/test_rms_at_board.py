"""The RMS reprojection error as a length at the board: results.json, summary.csv and the report's summary table."""
from __future__ import annotations

import csv

import pytest

from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.results.model import read_results
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.report.pages.summary import summary_rows
from lps_gui.sim.points import simulate_point_session

MM_PER_PX = 500.0 / 600.0  # small_spec: the board faces the camera 500 mm away, fx = fy = 600 px


@pytest.mark.parametrize("noise_px", [0.1, 0.4])
def test_the_rms_at_the_board_is_the_corner_noise_times_the_truth_scale(tmp_path, noise_px):
    spec = small_spec(seed=2, views=12, noise_px=noise_px)
    simulate_point_session(spec, tmp_path / "s")
    results = estimate_session(tmp_path / "s")
    p = results["parameters"]
    truth_um = 1e3 * noise_px * MM_PER_PX  # the simulator's corner noise, at the board
    assert p["rms_um_at_board"] == pytest.approx(truth_um, rel=0.1)  # residuals: noise less the fitted dof
    assert p["rms_um_at_board"] == pytest.approx(1e3 * p["rms_px"] * MM_PER_PX, rel=0.02)
    rows = {r[0]: r for r in csv.reader((tmp_path / "s" / "summary.csv").open())}
    assert float(rows["rms_reprojection_at_board"][1]) == pytest.approx(p["rms_um_at_board"], rel=1e-3)
    shown = [r for r in summary_rows(read_results(tmp_path / "s")) if r.name == "RMS reprojection error at the board"]
    assert len(shown) == 1 and shown[0].value  # the report's and the GUI's summary table
