"""plan-rig's row against what `lps estimate` reports on a simulated session of the proposed layout (SPEC 13)."""
from __future__ import annotations

import numpy as np

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.rig import intrinsics_from_lens
from lps_gui.core.planning.rows import propose_row
from lps_gui.core.planning.target_presets import row_spec
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session

PAPER_CAMERA = intrinsics_from_lens(8.0, 3.45, (1920, 1080))


def test_the_proposed_row_predicts_the_sigma_lps_estimate_reports_within_20_percent(tmp_path):
    plan = propose_row(PAPER_CAMERA, (1524.0,), wanted_sigma_um=6.0)
    spec = row_spec("planned-row", plan.board, PAPER_CAMERA, plan.n_targets, plan.pitch_mm[0], plan.distance_mm,
                    Plan(start_mm=0.0, stop_mm=1524.0, step_mm=12.7), seed=5, noise_px=0.1, errors=None)
    session = simulate_point_session(spec, tmp_path / "row")
    results = estimate_session(session.folder)
    reported = float(np.median([p["sigma_um"] for p in results["positions"][1:]]))
    assert len(results["targets"]) == plan.n_targets
    assert abs(plan.sigma_um_median / reported - 1.0) < 0.2, (plan.sigma_um_median, reported)
