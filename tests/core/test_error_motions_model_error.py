"""Issue 35: the error motions carry the held intrinsics' measured lens-model error (``model_error`` in
intrinsics.json) through the poses' sensitivity to them.

Point-level, the paper's two-depth rig (31 stops over 300 mm, 0.1 px noise): held intrinsics off by a model error
along (k1, k2, k3) tilt the pitch and yaw profiles against those of the true intrinsics (same corners) far beyond
the corners' noise; with that error's covariance the angles' sigmas cover the shift.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.metrology.error_motions import error_motions
from lps_gui.core.metrology.lens_tilts import held_intrinsics_error
from lps_gui.core.models.pose_model import solve_poses
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.core.truth.two_depth import observe_stops, two_depth_rig

STOPS = np.arange(0.0, 301.0, 10.0)


@pytest.fixture(scope="module")
def rig_views():
    tr = two_depth_rig(300.0, errors=StageErrorModel(), seed=0)
    return tr, observe_stops(tr, STOPS, noise_px=0.1, seed=0)


def test_the_angles_sigmas_cover_a_held_model_error(rig_views):
    tr, views = rig_views
    true = tr.rig.intrinsics
    noise = np.diag([1.0, 1.0, 0.25, 0.25, 1e-8, 1e-8, 1e-10, 1e-10, 1e-8])
    u = np.zeros(9)
    u[[4, 5, 8]] = [2e-3, -4e-3, 2e-3]  # a radial compromise of the kind a rational lens leaves in k1-k3
    model = np.outer(u, u)
    held = replace(true.with_vector(true.vector() + u), covariance=noise + model)
    ref = error_motions(solve_poses(views.observations, replace(true, covariance=noise)), STOPS)
    sol = solve_poses(views.observations, held)
    plain = error_motions(sol, STOPS)
    carried = error_motions(sol, STOPS, lens=held_intrinsics_error(sol.intrinsics_gradient, model))
    before, after = [], []
    for name in ("pitch", "yaw"):
        shift = carried.values[name] - ref.values[name]
        shift = shift - np.nanmean(shift)  # the profiles' shape (a constant is the reference stop's)
        before.append(np.nanmax(np.abs(shift) / plain.centred_sigmas[name]))
        after.append(np.nanmax(np.abs(shift) / carried.centred_sigmas[name]))
    assert max(before) > 3.0, before  # noise-only sigmas: the pitch profile 3.7 sigma off
    assert max(after) < 2.0, after  # carried: within 1 sigma
    assert held_intrinsics_error(sol.intrinsics_gradient, np.zeros((9, 9))) is None
