"""Out-of-plane motion of an XY gantry against the simulator's truth."""
from __future__ import annotations

import numpy as np

from lps_gui.core.estimator.estimate import EstimateOptions, estimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.metrology.planar_flatness import out_of_plane
from lps_gui.core.truth.simulate import paper_planar_spec, simulate_views
from lps_gui.core.truth.stage_errors import ErrorProfile, PlanarErrorModel, StageErrorModel


def test_out_of_plane_bow_is_recovered_with_honest_sigma():
    # X carries a 40 um bow out of the plane (a half sine over the travel); no tilts, so truth is the carriage's
    bow = ErrorProfile(amplitude=40.0, period_mm=280.0)
    errors = PlanarErrorModel(StageErrorModel(straightness_um=(ErrorProfile(), bow)), StageErrorModel(), 0.0)
    z2, rms = [], []
    for seed in range(3):
        spec = paper_planar_spec(seed=seed, errors=errors)
        views = simulate_views(spec)
        st = views.stops
        obs = Observations(spec.rig.board, spec.rig.intrinsics, views.corners_px, [s.target_mm for s in st],
                           [1] * len(st), [1] * len(st), [s.index for s in st], approach=[s.approach for s in st])
        est = estimate(obs, EstimateOptions(detect_outliers=False))
        X = spec.rig.board.object_points()
        oop = out_of_plane(est.state, X, obs.corners_px, obs.mask(), obs.target_mm, est.used)
        T = obs.target_mm
        design = np.column_stack([np.ones(len(T)), T])
        truth = views.pose.normal_um - design @ np.linalg.lstsq(design, views.pose.normal_um, rcond=None)[0]
        err = oop.normal_um - truth
        rms.append(np.sqrt(np.mean(err**2)))
        z2.append(np.mean((err / oop.sigma_um) ** 2))
    # the truth spans ~40 um; per view about 14 um of noise along the viewing direction on this rig
    assert np.ptp(truth) > 30.0
    assert 0.4 < np.mean(z2) < 2.5, z2
    assert np.mean(rms) < 1.3 * np.sqrt(np.mean(oop.sigma_um**2)), (rms, np.mean(oop.sigma_um))
