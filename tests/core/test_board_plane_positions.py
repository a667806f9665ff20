"""Positions at the board plane on a stage with angular motions (issue 35): the line model's misfit is not the
corners' noise. One point-level session of the small rig with the honesty campaign's ``motions`` profiles."""
from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.estimator.board_plane_positions import (
    POSITION_MODEL_BOARD_PLANE,
    POSITION_MODEL_POSE_SCALE,
    line_model_rejected,
)
from lps_gui.core.estimator.estimate import estimate
from lps_gui.core.truth.simulate import board_plane_positions, observations_of, simulate_views, small_spec
from lps_gui.core.truth.stage_errors import ErrorProfile, StageErrorModel, TruePose

FLAT = StageErrorModel(scale_ppm=100.0, periodic_um=5.0, pitch_mm=8.0, backlash_um=4.0, repeatability_um=1.0)
# benchmarks/honesty.py's motions stage over 22 mm: a sag, waves, roll 2000, pitch 1320, yaw 400 urad
MOTIONS = replace(FLAT, straightness_um=(ErrorProfile(poly=(0.0, 0.0, -9.68 / 0.022**2)), ErrorProfile(amplitude=5.0, period_mm=30.0)),
                  roll_urad=ErrorProfile(amplitude=2000.0, period_mm=40.0), pitch_urad=ErrorProfile(poly=(0.0, 1320.0 / 0.022)),
                  yaw_urad=ErrorProfile(amplitude=400.0, period_mm=30.0, phase_rad=0.5))
NOISE_PX = 0.05


def _session(errors: StageErrorModel, seed: int = 0):
    spec = small_spec(seed=seed, views=12, noise_px=NOISE_PX, directions="both", runs=2, errors=errors)
    views = simulate_views(spec)
    obs = observations_of(spec, views)
    t = views.truth
    pose = TruePose(np.asarray(t["axis_mm"]), np.asarray(t["straightness_um"]), np.asarray(t["angles_urad"]))
    return obs, estimate(obs), board_plane_positions(spec.rig, pose)


def _z2(est, truth_mm) -> float:
    ok = est.used.copy()
    ref = est.reference_view
    ok[ref] = False
    err = (est.state.s - (truth_mm - truth_mm[ref]))[ok]
    return float(np.mean((err / est.sigma_s_mm[ok]) ** 2))


def test_on_a_stage_with_angles_the_sigma_is_the_corners_noise_and_the_positions_honest():
    obs, est, truth = _session(MOTIONS)
    assert est.position_model == POSITION_MODEL_BOARD_PLANE
    assert est.line_model_sigma_px > 3 * NOISE_PX  # the line model's misfit (roll x distance, yaw)
    assert 0.8 * NOISE_PX < est.sigma_px < 1.2 * NOISE_PX  # the per-view poses' residuals: the corners' noise
    assert 0.4 < _z2(est, truth) < 2.0  # was ~0.01: sigma ~10x too large
    steps = est.step_sigma_mm[np.isfinite(est.step_sigma_mm)]
    assert steps.size == obs.K - 4  # every step but the first of each run and direction (2 x 2)
    assert np.all(steps < 2 * np.nanmax(est.sigma_s_mm))


def test_on_a_stage_the_line_model_fits_nothing_changes():
    obs, est, truth = _session(FLAT)
    assert est.position_model == "line" and est.line_model_sigma_px is None
    assert 0.8 * NOISE_PX < est.sigma_px < 1.2 * NOISE_PX
    assert 0.4 < _z2(est, truth) < 2.0


def test_the_variance_ratio_test():
    assert not line_model_rejected(1.002, 5129, 1.0, 4896)  # noise: F 1.04 on (233, 4896) dof
    assert line_model_rejected(1.05, 5129, 1.0, 4896, material=1.0)  # a misfit 5 % of the noise's variance: F 2.1
    assert not line_model_rejected(1.05, 5129, 1.0, 4896)  # ... significant, not material (the paper close-up)
    assert line_model_rejected(1.9, 5129, 1.0, 4896)  # min-step, settling on the motions stage
    assert not line_model_rejected(2.5, 20, 1.0, 15)  # a misfit as large as the noise, not significant on 20 dof
    assert not line_model_rejected(400.0, 0, 1.0, 5000)  # no redundancy: no judgement
    assert not line_model_rejected(2.5, 5000, 1.0, 5000)  # not nested: no judgement


def _nested_fits(misfit: float, draws: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Residual variances of a line fit y = a_g + b x per group (one shared slope: the line model) and of its
    nesting fit y = a_g + b_g x (each group its own: the per-view fit) to the same unit-noise data, whose true
    slopes spread by ~``misfit`` (sd) across the groups. Returns (sigma2_line, sigma2_groups, dof_line, dof_groups)."""
    groups, n = 12, 20
    x = np.linspace(-1.0, 1.0, n)
    slopes = misfit * np.linspace(-1.6, 1.6, groups)[:, None]  # sd ~ misfit
    y = slopes * x + rng.standard_normal((draws, groups, n))
    yc = y - y.mean(axis=2, keepdims=True)  # each group's offset removed (both fits have it)
    xc = x - x.mean()
    own = yc - (yc @ xc / (xc @ xc))[..., None] * xc
    shared = yc - (yc @ xc).sum(axis=1)[:, None, None] / (groups * (xc @ xc)) * xc
    dof_groups, dof_line = groups * (n - 2), groups * (n - 1) - 1
    return (shared**2).sum(axis=(1, 2)) / dof_line, (own**2).sum(axis=(1, 2)) / dof_groups, dof_line, dof_groups


def test_the_misfit_switch_rejects_at_its_stated_rate():
    """The switch is an F-test at a stated false-switch rate: where the line model holds, the share of draws
    it switches is alpha (the two fits' variances share the noise: tested as independent, it would switch
    in ~0 % at alpha 5 %); slopes that spread by twice the noise's sd (a material misfit, ratio ~2.4) switch every draw."""
    rng = np.random.default_rng(0)
    draws = 4000
    s2_line, s2_groups, dof_line, dof_groups = _nested_fits(0.0, draws, rng)
    for alpha in (0.05, 0.2):
        rate = np.mean([line_model_rejected(a, dof_line, b, dof_groups, alpha, material=1.0)
                        for a, b in zip(s2_line, s2_groups)])
        assert abs(rate - alpha) < 4 * np.sqrt(alpha * (1 - alpha) / draws), (alpha, rate)
    kept = sum(line_model_rejected(a, dof_line, b, dof_groups, material=1.0) for a, b in zip(s2_line, s2_groups))
    assert kept <= 12  # MISFIT_ALPHA 0.1 %: 4 expected of 4000
    s2_line, s2_groups, dof_line, dof_groups = _nested_fits(2.0, 200, rng)
    assert all(line_model_rejected(a, dof_line, b, dof_groups) for a, b in zip(s2_line, s2_groups))


def test_a_row_of_targets_on_a_stage_with_angles_takes_each_stops_full_pose():
    """SPEC 13's row model holds one orientation and one unknown per stop with the targets' poses: a roll's
    sideways path and a yaw are its misfit (0.33 px on 0.1 px corners). The positions come from every stop's
    full pose (the pose model, with the targets'), at the first target's centre, with the corners' noise."""
    from lps_gui.core.planning.target_presets import small_row_spec

    travel = 340.0
    m = travel / 1000.0
    errors = replace(FLAT, straightness_um=(ErrorProfile(poly=(0.0, 0.0, -9.68 / m**2)),
                                            ErrorProfile(amplitude=5.0, period_mm=30.0 / 22.0 * travel)),
                     roll_urad=ErrorProfile(amplitude=2000.0, period_mm=40.0 / 22.0 * travel),
                     pitch_urad=ErrorProfile(poly=(0.0, 1320.0 / m)),
                     yaw_urad=ErrorProfile(amplitude=400.0, period_mm=30.0 / 22.0 * travel, phase_rad=0.5))
    spec = small_row_spec(seed=0, noise_px=0.1, errors=errors)
    views = simulate_views(spec)
    est = estimate(observations_of(spec, views))
    t = views.truth
    truth = board_plane_positions(spec.rig, TruePose(np.asarray(t["axis_mm"]), np.asarray(t["straightness_um"]),
                                                     np.asarray(t["angles_urad"])))
    assert est.position_model == POSITION_MODEL_BOARD_PLANE and est.line_model_sigma_px > 0.2
    assert 0.08 < est.sigma_px < 0.12  # the corners' 0.1 px (was the row model's 0.33 px)
    assert 0.4 < _z2(est, truth) < 2.0
    assert np.all(np.isfinite(est.step_sigma_mm[1:]))  # one run, one direction: every step after the first
    L = np.zeros((1, obs_k := est.used.size))
    L[0, -1], L[0, 0] = 1.0, -1.0  # the whole travel: its sigma is that of the last stop relative to the first
    assert np.sqrt(est.functional_covariance(L)[0, 0]) == pytest.approx(est.sigma_s_mm[-1], rel=1e-6)


def test_a_row_that_would_self_calibrate_keeps_the_full_poses_on_a_stage_with_angles():
    """A row self-calibrates by default (pipeline.estimate.resolve_self_calibration), but freed intrinsics in a
    model of one orientation absorb the angles: where the row model (intrinsics held) leaves the stage's angles,
    the estimate is the held one with every stop's full pose."""
    from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
    from lps_gui.core.planning.target_presets import small_row_spec
    from lps_gui.pipeline.estimate import estimate_with_self_calibration, make_options

    travel = 340.0
    errors = replace(FLAT, roll_urad=ErrorProfile(amplitude=2000.0, period_mm=40.0 / 22.0 * travel),
                     yaw_urad=ErrorProfile(amplitude=400.0, period_mm=30.0 / 22.0 * travel, phase_rad=0.5))
    spec = small_row_spec(seed=0, noise_px=0.1, errors=errors)
    obs = observations_of(spec, simulate_views(spec))
    cov = np.diag((1e-3 * np.abs(obs.intrinsics.vector()) + 1e-4) ** 2)  # a calibration's covariance: a prior
    obs = replace(obs, intrinsics=replace(obs.intrinsics, covariance=cov))
    assert cov.shape == (len(INTRINSIC_NAMES),) * 2
    est = estimate_with_self_calibration(obs, make_options("joint", None))
    assert est.position_model == POSITION_MODEL_BOARD_PLANE


def test_a_misfit_under_the_noise_still_switches_when_the_line_models_scale_is_rejected(monkeypatch):
    """The ASME min-step test on the motions stage (2 places 22 mm apart, pitch 1320 urad between them): the
    line model's misfit (0.016 px) stays under the corners' noise; where the variance test does not see it
    (here: turned off; the F-test now switches this session to the board plane), the line model reads the
    pitch's Abbe shift 0.5 % short: +157 ppm of scale against the board-plane truth, 3.5 sigma (was: line model
    kept, scale +145 ppm outside U in 8 of 10 seeds of the campaign)."""
    from lps_gui.core.estimator import board_plane_positions as bpp

    monkeypatch.setattr(bpp, "line_model_rejected", lambda *a, **k: False)
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.planning.presets import min_step_plan_fields

    spec = replace(small_spec(seed=0, noise_px=0.02, errors=replace(MOTIONS, dead_band_um=3.0, repeatability_um=0.1)),
                   plan=Plan(**min_step_plan_fields(0.0, 22.0, steps=5, locations=2, frames=2)))
    views = simulate_views(spec)
    obs = observations_of(spec, views)
    t = views.truth
    truth = board_plane_positions(spec.rig, TruePose(np.asarray(t["axis_mm"]), np.asarray(t["straightness_um"]),
                                                     np.asarray(t["angles_urad"])))
    est = estimate(obs)
    assert est.line_model_sigma_px is None  # not the variance test: the line model's positions, the poses' scale
    assert est.position_model == POSITION_MODEL_POSE_SCALE
    target = np.asarray(obs.target_mm)
    far = target > 11.0
    L = np.where(est.used, np.where(far, 1.0 / far[est.used].sum(), -1.0 / (~far)[est.used].sum()), 0.0)[None]
    sigma = float(np.sqrt(est.functional_covariance(L)[0, 0]))
    err = float(L[0] @ (est.state.s - truth))  # the far place's mean position minus the near one's, against truth
    assert abs(err) < 3 * sigma, (err, sigma)


def test_a_kept_line_models_positions_take_the_corners_noise_not_its_misfit(monkeypatch):
    """The same min-step session, the variance test off: the line model is kept, but its a-posteriori sigma
    is noise plus misfit (0.0257 px where the simulator drew 0.020). The misfit is what the model cannot
    follow, not scatter of the positions: sized with it, the campaign's min-step motions cell had per-stop
    (error/sigma)^2 0.52 and E, M 0.38, 0.16. The positions' noise is the per-view fit's, the drawn noise."""
    from lps_gui.core.estimator import board_plane_positions as bpp
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.planning.presets import min_step_plan_fields

    monkeypatch.setattr(bpp, "line_model_rejected", lambda *a, **k: False)
    noise_px = 0.02
    spec = replace(small_spec(seed=0, noise_px=noise_px, errors=replace(MOTIONS, dead_band_um=3.0,
                                                                        repeatability_um=0.1)),
                   plan=Plan(**min_step_plan_fields(0.0, 22.0, steps=5, locations=2, frames=2)))
    est = estimate(observations_of(spec, simulate_views(spec)))
    assert est.position_model == POSITION_MODEL_POSE_SCALE  # the line model's positions, kept
    assert abs(est.sigma_px / noise_px - 1.0) < 0.05, est.sigma_px
