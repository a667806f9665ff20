"""A session end to end: ISO 230-2 A and R against the simulator's truth (issue 35).

The point-level small preset (per-view noise ~20 um, 12 targets, 2 runs each way):
before the noise correction A came out 150-220 um above the truth on U 65 um in
seeds 0-5; after it, within U (seed 4 here: error -5 um, U 154 um).
"""
from __future__ import annotations

import pytest

from lps_gui.core.truth.simulate import small_spec
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session
from lps_gui.sim.truth_figures import figure_checks


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("iso_noise") / "s"
    simulate_point_session(small_spec(seed=4, views=12, directions="both", runs=2), folder)
    return estimate_session(folder)


def test_a_and_r_are_within_their_u_of_the_truth(results):
    checks = {c["figure"]: c for c in figure_checks(results)}
    for name in ("A", "R", "E", "B", "M"):
        assert abs(checks[name]["error"]) <= checks[name]["U_k2"], name


def test_the_measured_figures_and_the_noise_share_are_kept(results):
    iso = results["figures"]["iso230_2"]
    corr = iso["noise_correction"]["A_um"]
    assert corr["measured"] > iso["A_um"] and corr["bias"] > 0 and corr["u_noise"] > 0
    assert any("noise" in n for n in iso["notes"])
