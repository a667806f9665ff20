"""The planning aid predicts what the estimator then reports on a simulated session."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.estimator.estimate import estimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.rig import intrinsics_from_lens, predict_rig
from lps_gui.core.truth.simulate import observations_of, simulate_views, small_planar_spec, small_spec
from lps_gui.errors import InputError


def test_planar_prediction_within_20_percent_of_the_sigma_measured_on_a_simulated_session():
    spec = small_planar_spec(seed=21, noise_px=0.2)
    pred = predict_rig(spec.rig.board, spec.rig.intrinsics, 500.0, spec.plan, noise_px=0.2)
    assert pred.board_in_view and pred.targets_losing_board == 0
    views = simulate_views(spec)
    st = views.stops
    obs = Observations(spec.rig.board, spec.rig.intrinsics, views.corners_px, [s.target_mm for s in st],
                       [1] * len(st), [1] * len(st), [s.index for s in st], approach=[s.approach for s in st])
    est = estimate(obs)
    measured = float(np.median(np.sqrt(np.mean((1e3 * est.sigma_s_mm[1:]) ** 2, axis=1))))
    assert abs(pred.sigma_um_median / measured - 1.0) < 0.2, (pred.sigma_um_median, measured)


def test_line_prediction_within_20_percent_of_the_sigma_measured_on_a_simulated_session():
    spec = small_spec(seed=4)
    pred = predict_rig(spec.rig.board, spec.rig.intrinsics, 500.0, spec.plan, noise_px=spec.noise_px)
    est = estimate(observations_of(spec, simulate_views(spec)))
    measured = float(np.median(1e3 * est.sigma_s_mm[1:]))
    assert abs(pred.sigma_um_median / measured - 1.0) < 0.2, (pred.sigma_um_median, measured)


def test_a_camera_too_close_loses_the_board_and_says_so():
    spec = small_planar_spec()
    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(400.0, 300.0), step_mm=(50.0, 50.0))
    pred = predict_rig(spec.rig.board, spec.rig.intrinsics, 300.0, plan)
    assert not pred.board_in_view
    assert pred.targets_losing_board > 0 and pred.first_target_losing_board is not None
    assert any("move the camera back" in n for n in pred.notes)


def test_closer_camera_predicts_smaller_sigma():
    spec = small_planar_spec()
    far = predict_rig(spec.rig.board, spec.rig.intrinsics, 700.0, spec.plan)
    near = predict_rig(spec.rig.board, spec.rig.intrinsics, 450.0, spec.plan)
    assert near.sigma_um_median < far.sigma_um_median


def test_intrinsics_from_lens_and_bad_input():
    intr = intrinsics_from_lens(8.18, 5.86, (1920, 1080))
    assert intr.fx == pytest.approx(1395.9, abs=0.1)
    with pytest.raises(InputError):
        intrinsics_from_lens(0.0, 5.86, (1920, 1080))
    spec = small_planar_spec()
    with pytest.raises(InputError, match="distance"):
        predict_rig(spec.rig.board, spec.rig.intrinsics, -1.0, spec.plan)
