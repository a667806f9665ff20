"""The lens-model error a calibration measures from its own views (issue 35): nothing through an exact
5-coefficient lens, a significant spread through a lens with rational and thin-prism terms."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
from lps_gui.core.intrinsics.model_error import EIG_SIGNIFICANT, excess_covariance
from lps_gui.core.truth.realism import REALISM
from lps_gui.errors import InputError
from lps_gui.io.intrinsics_file import intrinsics_from_dict, intrinsics_to_dict, model_error_covariance
from lps_gui.sim.images import sample_intrinsics_poses

# the paper's camera and the two-depth campaign's calibration board (benchmarks/honesty.py)
INTR = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 960.0, 540.0)
BOARD = Board(cols=10, rows=7, square_mm=30.0)
NOISE_PX = 0.013  # the rendered sets' corner noise


def view_set(lens, seed: int, n: int = 10) -> np.ndarray:
    """Corners (n, N, 2) of a campaign-like varied-pose set, through ``lens`` (None: the exact 5-coefficient one)."""
    rng = np.random.default_rng(seed)
    X = BOARD.object_points()
    out = []
    for R, t in sample_intrinsics_poses(BOARD, INTR, n, rng):
        x = X @ np.asarray(R).T + np.asarray(t)
        out.append(project(x, INTR).uv if lens is None else lens.project(x, INTR))
    return np.array(out) + rng.normal(0.0, NOISE_PX, (n, len(X), 2))


def test_an_exact_lens_adds_nothing():
    uv = list(view_set(None, 0))
    cal = calibrate_intrinsics(BOARD.object_points(), uv, INTR.image_size, warp="off", model_error=True)
    plain = calibrate_intrinsics(BOARD.object_points(), uv, INTR.image_size, warp="off")
    rec = cal.intrinsics.extra["model_error"]
    assert max(rec["jackknife_eigenvalues"]) < EIG_SIGNIFICANT
    assert not np.any(model_error_covariance(cal.intrinsics))
    assert np.allclose(cal.intrinsics.covariance, plain.intrinsics.covariance, rtol=1e-9, atol=0.0)
    assert not any("move with the view set" in w for w in cal.warnings)


def test_a_lens_the_model_cannot_follow_is_measured():
    lens = REALISM["on"].lens(INTR)  # the campaign's realism: rational k4-k6, thin prism s1-s4
    cal = calibrate_intrinsics(BOARD.object_points(), list(view_set(lens, 0)), INTR.image_size, warp="off",
                               model_error=True)
    model = model_error_covariance(cal.intrinsics)
    assert max(cal.intrinsics.extra["model_error"]["jackknife_eigenvalues"]) > EIG_SIGNIFICANT
    assert np.all(np.linalg.eigvalsh(model) > -1e-12 * np.abs(model).max())
    noise = cal.intrinsics.covariance - model
    assert np.max(np.diag(model) / np.diag(noise)) > 1.0  # some parameter's sigma grows by more than sqrt(2)
    assert any("move with the view set" in w for w in cal.warnings)
    again = intrinsics_from_dict(intrinsics_to_dict(cal.intrinsics))  # intrinsics.json keeps it
    assert np.allclose(model_error_covariance(again), model)
    assert np.allclose(again.covariance, cal.intrinsics.covariance)


def test_excess_over_the_noise_recovers_an_injected_spread():
    rng = np.random.default_rng(3)
    n, noise = 12, np.diag([4.0, 1.0, 0.25])
    drop = np.array([noise * (1.0 + 2.0 * (j == 0)) / (n - 1) for j in range(n)])  # view 0 has leverage
    C_j = noise + drop
    base = np.array([rng.multivariate_normal(np.zeros(3), c) for c in drop])
    null = excess_covariance(base, C_j, noise)
    assert not np.any(null.covariance)
    u = np.array([1.0, -1.0, 0.0]) / np.sqrt(2)
    spread = base + np.outer(rng.choice([-1.0, 1.0], n) * 3.0, u)  # 3 units along u, far beyond the noise
    found = excess_covariance(spread, C_j, noise)
    along = u @ found.covariance @ u  # the jackknife's (n-1)/n sum of 3^2, less the noise's share
    assert along == pytest.approx((n - 1) * 9.0, rel=0.1)
    assert abs(np.array([1.0, 1.0, 0.0]) @ found.covariance @ np.array([1.0, 1.0, 0.0])) < 0.2 * along


def test_a_malformed_model_error_is_refused():
    d = intrinsics_to_dict(INTR)
    assert model_error_covariance(intrinsics_from_dict(d)) is None  # older files: nothing added
    d["model_error"] = {"covariance": [[1.0, 2.0]]}
    with pytest.raises(InputError, match="model_error.covariance"):
        model_error_covariance(intrinsics_from_dict(d))
