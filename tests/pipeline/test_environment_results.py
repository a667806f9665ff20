"""The environment of session.json corrects the length scale and fills the uncertainty budget."""
import json
from dataclasses import replace

import pytest

from lps_gui.core.truth.simulate import small_spec
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("env") / "s"
    simulate_point_session(replace(small_spec(seed=5, views=12, directions="both", runs=2)), folder)
    return folder


def _with_environment(session, env):
    meta = json.loads((session / "session.json").read_text())
    meta["environment"] = env
    (session / "session.json").write_text(json.dumps(meta))


def test_board_at_23c_with_23ppm_changes_scale_by_plus_69ppm(session, tmp_path):
    _with_environment(session, {"board_temperature_c": 20.0, "board_cte_ppm_per_k": 23.0})
    at20 = estimate_session(session, out_dir=tmp_path / "at20")
    _with_environment(session, {"board_temperature_c": 23.0, "board_cte_ppm_per_k": 23.0,
                                "square_mm_uncertainty_um": 1.0, "notes": "lab A"})
    at23 = estimate_session(session, out_dir=tmp_path / "at23")
    delta = at23["figures"]["single_run"]["scale_ppm"] - at20["figures"]["single_run"]["scale_ppm"]
    assert delta == pytest.approx(69.0, abs=3.0)
    assert at23["environment"]["board_scale_correction_ppm"] == pytest.approx(69.0)
    assert at23["environment"]["notes"] == "lab A"
    assert at23["board"]["square_mm"] == at20["board"]["square_mm"]  # nominal size kept, the used one recorded
    assert at23["environment"]["square_mm_used"] > at23["environment"]["square_mm_nominal"]
    unc = at23["uncertainty"]
    sources = {r["source"]: r for r in unc["budget"]}
    assert {"corner noise", "intrinsics", "board square size", "board temperature"} <= set(sources)
    assert sources["board temperature"]["contribution_um"] > 0
    assert sources["board square size"]["type"] == "B"
    assert unc["expanded_k2_um"] > 0 and unc["coverage_factor"] == 2
    # A's U: the noise-corrected A's own noise u (Monte Carlo) with the budget's rows that are not per-view noise
    noise_u = at23["figures"]["iso230_2"]["noise_correction"]["A_um"]["u_noise"]
    other = [r["contribution_um"] for r in unc["budget"]
             if r["contribution_um"] is not None and r["source"] not in ("corner noise", "reference view noise")]
    assert unc["figures_k2"]["A_um"] == pytest.approx(2 * (noise_u**2 + sum(c * c for c in other)) ** 0.5)


def test_without_environment_nothing_is_corrected(session, tmp_path):
    _with_environment(session, {})
    res = estimate_session(session, out_dir=tmp_path / "none")
    assert res["environment"]["board_scale_correction_ppm"] == 0.0
    assert "board temperature" in res["uncertainty"]["not_in_u"]
