"""The row planner's prediction against what the estimator reports on a simulated session of the layout."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout, observe
from lps_gui.core.models.target_model import TargetObservations, solve_targets
from lps_gui.core.planning.rig import intrinsics_from_lens
from lps_gui.core.planning.rows import DISTANCE_STEP_MM, RowPlan, plan_row, propose_row
from lps_gui.errors import InputError

PAPER_CAMERA = intrinsics_from_lens(8.0, 3.45, (1920, 1080))


def simulated_session(plan: RowPlan, seed: int, noise_px: float = 0.1):
    """The plan's layout as mounted (tilts of 10 mrad, offsets of 2 mm), a camera turned 10-20 mrad, stage noise of 5 um."""
    layout, R, t, targets_mm = plan.geometry()
    rng = np.random.default_rng(seed)
    T = len(layout.targets)
    Q = np.stack([np.eye(3)] + [exp_so3(rng.normal(0.0, 0.01, 3)) for _ in range(T - 1)])
    p = layout.p + np.r_[np.zeros((1, 3)), rng.normal(0.0, 2.0, (T - 1, 3))]
    mounted = TargetLayout(layout.targets, Q, p)
    C = -t @ R  # camera centres in the world
    x_true = targets_mm + rng.normal(0.0, 0.005, targets_mm.shape)
    C[:, : targets_mm.shape[1]] += x_true - targets_mm
    R_sim = exp_so3(np.array([0.01, -0.02, 0.005])) @ R
    t_sim = -C @ R_sim.T
    uv = observe(mounted, PAPER_CAMERA, R_sim, t_sim, noise_px=noise_px, seed=seed, border_px=2.0)
    return TargetObservations(list(layout.targets), uv, targets_mm, [f"v{i:03d}.png" for i in range(len(uv))]), x_true


@pytest.mark.parametrize("travel, distance, stops", [((1524.0,), 800.0, (121,)), ((1524.0, 1016.0), 1500.0, (9, 7))])
def test_predicted_sigma_within_20_percent_of_what_the_estimator_reports(travel, distance, stops):
    plan = plan_row(PAPER_CAMERA, distance, travel, stops, noise_px=0.1)
    obs, x_true = simulated_session(plan, seed=3)
    sol = solve_targets(obs, PAPER_CAMERA)  # sigmas from the fit's own a-posteriori noise
    reported = float(np.median(sol.sigma_s[1:]) * 1e3)
    assert abs(plan.sigma_um_median / reported - 1.0) < 0.2, (plan.sigma_um_median, reported)
    error = sol.s - (x_true - x_true[sol.reference])  # the stage frame is the plan's frame to first order
    if len(travel) == 1:  # the planar frame turns by the squareness; the line's positions compare directly
        z2 = np.mean((error[1:] / sol.sigma_s[1:]) ** 2)
        assert 0.4 < z2 < 2.5, z2


def test_the_proposed_distance_is_the_farthest_meeting_the_wanted_sigma():
    plan = propose_row(PAPER_CAMERA, (1524.0,), wanted_sigma_um=5.0)
    assert plan.sigma_um_median <= 5.0 and plan.n_targets >= 3
    farther = plan_row(PAPER_CAMERA, plan.distance_mm + DISTANCE_STEP_MM, (1524.0,))
    assert farther.sigma_um_median > 5.0
    assert plan.make_targets_command().startswith(f"lps make-targets row --count {plan.n_targets} --inner-corners 10x7")


def test_an_unreachable_sigma_is_a_one_line_error():
    with pytest.raises(InputError, match="longer lens") as exc:
        propose_row(PAPER_CAMERA, (1524.0,), wanted_sigma_um=0.5)
    assert "\n" not in str(exc.value)
