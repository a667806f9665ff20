"""The row / constellation model (SPEC 13) against simulator truth and finite differences."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES, CameraIntrinsics
from lps_gui.core.geometry.rotation import exp_so3, log_so3
from lps_gui.core.geometry.target_rig import TargetLayout, observe, row_layout
from lps_gui.core.geometry.targets import pack_targets
from lps_gui.core.models.target_model import (
    N_COMMON,
    TargetObservations,
    _linearize,
    _retract,
    initial_solution,
    solve_targets,
)
from lps_gui.errors import DegenerateGeometryError
from tests.core.target_crb import crb_centred

PAPER_CAMERA = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 960.0, 540.0)  # 8 mm, 3.45 um pixels
ROW_BOARD = Board(10, 7, 30.0, type="charuco", marker_mm=22.0)
R_TRUE = exp_so3(np.array([0.01, -0.02, 0.005]))


def paper_x_axis(seed: int, n_targets: int = 6, stops: int = 121, pitch_mm: float = 12.7, noise_px: float = 0.1):
    """The paper's X axis: 1524 mm in 121 stops, six 10x7 targets of 30 mm at 340 mm pitch, 800 mm away."""
    targets = pack_targets([ROW_BOARD] * n_targets)
    layout = row_layout(targets, 340.0, tilt_sigma_rad=0.01, offset_sigma_mm=2.0, seed=seed)
    x = np.arange(stops) * pitch_mm
    rng = np.random.default_rng(100 + seed)
    s_true = x + rng.normal(0, 0.005, stops) + 0.004 * np.sin(2 * np.pi * x / 50)
    span = (n_targets - 1) * 340.0 + ROW_BOARD.size_mm[0]
    l0 = R_TRUE @ np.array([-(span - x[-1]) / 2, -90.0, 0]) + np.array([0, 0, 800.0])
    t = l0 + s_true[:, None] * (R_TRUE @ np.array([-1.0, 0, 0]))
    uv = observe(layout, PAPER_CAMERA, R_TRUE, t, noise_px=noise_px, seed=seed)
    return TargetObservations(targets, uv, x[:, None], [f"v{i:03d}.png" for i in range(stops)]), layout, s_true


def planar_constellation(seed: int, noise_px: float = 0.1, squareness_rad: float = 150e-6,
                         cols: int = 6, rows: int = 4, travel_mm=(1524.0, 1016.0), grid=(13, 9)):
    """A 1524 x 1016 mm planar grid against a 6 x 4 constellation of targets in one plane."""
    T = cols * rows
    targets = pack_targets([ROW_BOARD] * T)
    Q = np.stack([np.eye(3)] + [exp_so3(np.random.default_rng(seed).normal(0, 0.01, 3)) for _ in range(T - 1)])
    jj, ii = np.meshgrid(np.arange(cols), np.arange(rows))
    p = np.stack([340.0 * jj.ravel(), 300.0 * ii.ravel(), np.zeros(T)], axis=1)
    p[1:] += np.random.default_rng(seed + 1).normal(0, 2.0, (T - 1, 3))
    layout = TargetLayout(tuple(targets), Q, p)
    gx, gy = np.meshgrid(np.linspace(0, travel_mm[0], grid[0]), np.linspace(0, travel_mm[1], grid[1]))
    xy = np.stack([gx.ravel(), gy.ravel()], axis=1)
    rng = np.random.default_rng(200 + seed)
    true = xy + rng.normal(0, 0.004, xy.shape)
    true[:, 0] += -np.sin(squareness_rad) * true[:, 1]  # +Y motion leans towards -X: squareness
    true[:, 1] *= np.cos(squareness_rad)
    centre = np.array([((cols - 1) * 340 + 270) / 2, ((rows - 1) * 300 + 180) / 2, 0.0])
    origin = centre - np.array([travel_mm[0] / 2, travel_mm[1] / 2, 0.0])
    cam_world = origin + np.c_[true, np.zeros(len(true))]  # camera centre over the plane, 800 mm in front
    t = -(R_TRUE @ cam_world.T).T + np.array([0, 0, 800.0])
    uv = observe(layout, PAPER_CAMERA, R_TRUE, t, noise_px=noise_px, seed=seed)
    return TargetObservations(targets, uv, xy, [f"g{i:03d}.png" for i in range(len(xy))]), layout, true


@pytest.mark.parametrize("D,free_intrinsics", [(1, False), (2, False), (1, True), (2, True)])
def test_the_jacobian_blocks_match_central_differences(D, free_intrinsics):
    """Every column of the row / constellation model, with the 9 intrinsics as shared columns when they are
    selected (self-calibration)."""
    obs, _, _ = (paper_x_axis(0, n_targets=3, stops=12, pitch_mm=40.0) if D == 1
                 else planar_constellation(0, cols=3, rows=2, travel_mm=(400.0, 200.0), grid=(4, 3)))
    state = initial_solution(obs, PAPER_CAMERA)
    state["s"] = np.where(state["used"][:, None], state["s"], 0.0)
    C = N_COMMON
    if free_intrinsics:
        state["I"] = PAPER_CAMERA.with_vector(PAPER_CAMERA.vector() + [0, 0, 0, 0, -0.1, 0.05, 1e-3, -1e-3, 0.01]
                                              ).vector()  # distortion not zero, so its terms count
        C += 9
    T = len(obs.targets)
    view, corner = np.nonzero(np.isfinite(obs.corners_px[..., 0]) & state["used"][:, None])
    X, tj, uv = obs.own_points[corner], obs.which[corner], obs.corners_px[view, corner]
    lin = _linearize(state, X, tj, view, uv, PAPER_CAMERA, D)
    G = C + 6 * (T - 1)
    h = 1e-6

    def residual(dg, dv):
        return _linearize(_retract(state, dg, dv, D, T), X, tj, view, uv, PAPER_CAMERA, D, False).r

    for g in range(G):
        e = np.zeros(G)
        e[g] = h
        num = (residual(e, 0 * state["s"]) - residual(-e, 0 * state["s"])) / (2 * h)
        if g < C:
            ana = lin.Jc[:, :, g]
        else:
            j, k = divmod(g - C, 6)
            ana = np.where((tj == j + 1)[:, None], lin.Jt[:, :, k], 0.0)
        scale = max(np.abs(ana).max(), 1e-12)
        assert np.abs(num - ana).max() < 1e-5 * scale, f"global column {g}"
    for d in range(D):
        dv = np.zeros_like(state["s"])
        dv[:, d] = h
        num = (residual(np.zeros(G), dv) - residual(np.zeros(G), -dv)) / (2 * h)
        assert np.abs(num - lin.Jv[:, :, d]).max() < 1e-5 * np.abs(lin.Jv[:, :, d]).max()
    # a wrong term must fail: the tilt columns of N scaled by 1 %
    assert np.abs(1.01 * lin.Jc[:, :, 6] - lin.Jc[:, :, 6]).max() > 1e-5 * np.abs(lin.Jc[:, :, 6]).max()


def test_the_reported_sigmas_are_the_cramer_rao_bound_of_the_row_model():
    obs, layout, s_true = paper_x_axis(1, n_targets=3, stops=31, pitch_mm=20.0)
    sol = solve_targets(obs, PAPER_CAMERA)
    crb = crb_centred(obs, layout, s_true, 1, 0.1, PAPER_CAMERA)
    ratio = sol.sigma_centred[:, 0] / crb[:, 0] * (0.1 / sol.sigma_px)
    assert np.all(np.abs(ratio - 1) < 0.05), ratio


@pytest.mark.parametrize("seeds", [range(3), pytest.param(range(10), marks=pytest.mark.slow)])
def test_the_paper_x_axis_end_to_end_reaches_the_bound(seeds):
    errors, sigmas, z2, target_z = [], [], [], []
    for seed in seeds:
        obs, layout, s_true = paper_x_axis(seed)
        sol = solve_targets(obs, PAPER_CAMERA)
        assert sol.converged and sol.used.all()
        e = sol.s[:, 0] - s_true
        e -= e.mean()
        errors.append(e)
        sigmas.append(sol.sigma_centred[:, 0])
        z2.append(np.mean((e / sol.sigma_centred[:, 0]) ** 2))
        for j in range(1, len(obs.targets)):
            d = np.r_[log_so3(sol.Q[j] @ layout.Q[j].T), sol.p[j] - layout.p[j]]
            target_z.append(np.abs(d) / sol.target_sigma[j])
    errors, sigmas = np.array(errors), np.array(sigmas)
    assert 2.8e-3 < np.median(sigmas) < 4.0e-3  # SPEC 13: 3.7 um per stop (median, centred)
    assert np.sqrt(np.mean(errors ** 2)) < 1.3 * np.sqrt(np.mean(sigmas ** 2))
    assert 0.5 < np.mean(z2) < 2.0
    assert np.max(target_z) < 3.0


def test_a_planar_constellation_gives_positions_and_squareness():
    obs, layout, true = planar_constellation(0)
    sol = solve_targets(obs, PAPER_CAMERA)
    assert sol.converged and sol.used.all()
    e = sol.s - true
    e -= e.mean(axis=0)
    # the stage frame puts x along the fitted +X motion: compare in that frame (true rotated the same way)
    A, *_ = np.linalg.lstsq(obs.targets_mm - obs.targets_mm[0], true - true[0], rcond=None)
    a = A[0] / np.linalg.norm(A[0])
    G = np.array([[a[0], -a[1]], [a[1], a[0]]])
    e = (sol.s - sol.s.mean(0)) - (true - true.mean(0)) @ G
    z2 = np.mean((e / sol.sigma_centred) ** 2)
    assert 0.3 < z2 < 3.0
    assert np.sqrt(np.mean(e ** 2)) < 1.3 * np.sqrt(np.mean(sol.sigma_centred ** 2))
    axes = sol.planar_axes(obs.targets_mm)
    assert abs(axes["squareness_urad"] - 150.0) < 3 * axes["squareness_sigma_urad"]
    assert 0 < axes["squareness_sigma_urad"] < 20.0
    assert abs(axes["scale_x_ppm"]) < 3 * axes["scale_x_sigma_ppm"]
    assert abs(axes["scale_y_ppm"]) < 3 * axes["scale_y_sigma_ppm"]
    # the factored covariance gives each position's own sigma back
    g = np.zeros_like(sol.s)
    g[5, 1] = 1.0
    assert np.sqrt(sol.covariance.variance(g)) == pytest.approx(sol.sigma_s[5, 1], rel=1e-9)


def test_an_untied_target_is_a_one_line_error():
    obs, _, _ = paper_x_axis(0, n_targets=4, stops=121)
    far = obs.which == 3
    uv = obs.corners_px.copy()
    # target 3 seen only by views that see nothing else: no chain to target 0
    sees_3 = np.isfinite(uv[:, far, 0]).any(axis=1)
    uv[np.ix_(sees_3, ~far)] = np.nan
    obs = TargetObservations(obs.targets, uv, obs.targets_mm, obs.names)
    with pytest.raises(DegenerateGeometryError) as err:
        solve_targets(obs, PAPER_CAMERA)
    assert "target T3 is not tied to target T0" in str(err.value)


def test_the_targets_section_names_poses_sigmas_views_ties_and_stretch():
    from lps_gui.pipeline.results.targets import target_rows

    obs, layout, _ = paper_x_axis(2)
    sol = solve_targets(obs, PAPER_CAMERA)
    rows = target_rows(obs.targets, sol.Q, sol.p, sol.target_sigma, obs.corners_px, obs.targets_mm, sol.used)
    assert [r["id"] for r in rows] == [f"T{j}" for j in range(6)]
    assert rows[0]["p_sigma_mm"] == [0.0, 0.0, 0.0]  # the world frame
    for j, r in enumerate(rows[1:], start=1):
        assert np.abs(np.array(r["p_mm"]) - layout.p[j]).max() < 4 * max(r["p_sigma_mm"])
        assert 0 < r["ties"] <= r["views"]
    # the row is seen left to right: each target's stretch starts after the previous one's
    starts = [r["stretch_mm"][0][0] for r in rows]
    assert starts == sorted(starts) and rows[0]["stretch_mm"][0][0] == 0.0
    assert rows[-1]["stretch_mm"][1][0] == pytest.approx(120 * 12.7)


@pytest.mark.parametrize("D", [1, 2])
def test_the_intrinsics_gradient_matches_central_differences_of_the_solution(D):
    """d s / d intrinsics (what the total sigma propagates) against re-solving with moved intrinsics; on a
    plane the in-plane turn of the stage frame follows the positions, and its change is part of it."""
    obs, _, _ = (paper_x_axis(0, n_targets=3, stops=15, pitch_mm=40.0, noise_px=0.05) if D == 1
                 else planar_constellation(0, cols=3, rows=2, travel_mm=(400.0, 200.0), grid=(4, 3), noise_px=0.05))
    intr = CameraIntrinsics(PAPER_CAMERA.image_size, PAPER_CAMERA.camera_matrix, PAPER_CAMERA.dist,
                            covariance=np.eye(9))
    sol = solve_targets(obs, intr, tolerance=1e-15)
    v = intr.vector()
    for i, h in ((0, 0.5), (2, 0.2), (4, 1e-4)):
        moved = [solve_targets(obs, intr.with_vector(v + sign * h * np.eye(9)[i]), tolerance=1e-15).s
                 for sign in (1, -1)]
        num = (moved[0] - moved[1]) / (2 * h)
        ana = sol.intrinsics_gradient[:, :, i]
        assert np.nanmax(np.abs(num - ana)) < 1e-3 * np.nanmax(np.abs(ana)), INTRINSIC_NAMES[i]
