"""ISO 230-2 and single-run figures (SPEC 5) against hand-computed values and synthetic truth."""
import json
import math

import numpy as np
import pytest

from lps_gui.core.metrology.iso230 import (
    bidirectional_figures,
    check_specification,
    direction_signs,
    figures_for_session,
    single_run_figures,
)
from lps_gui.core.metrology.iso230_spectrum import deviation_spectrum
from lps_gui.errors import InputError

SQ2 = math.sqrt(2.0)

# ---------------------------------------------------------------- hand case: 3 targets x 2 runs x 2 directions
# targets 0, 10, 20 mm; deviations (um)
#   up   run 1:  0   2   4        up   run 2:  2   4   2
#   down run 1: -2  -1   0        down run 2: -4  -1   2
# x̄↑ = (1, 3, 3)     s↑ = |a-b|/√2 = (√2, √2, √2)
# x̄↓ = (-3, -1, 1)   s↓ = (√2, 0, √2)
# B_j = x̄↑ - x̄↓ = (4, 4, 2)           -> B = 4, B̄ = 10/3
# R_j↑ = 4 s↑ = 4√2 (all)              -> R↑ = 4√2;  R_j↓ = (4√2, 0, 4√2) -> R↓ = 4√2
# R_j = max(2s↑ + 2s↓ + |B_j|, R_j↑, R_j↓) = (4√2 + 4, 2√2 + 4, 4√2 + 2) -> R = 4 + 4√2
# E↑ = 3 - 1 = 2, E↓ = 1 - (-3) = 4, E = 3 - (-3) = 6
# M: (x̄↑ + x̄↓)/2 = (-1, 1, 2) -> M = 3
# A↑ = (3 + 2√2) - (1 - 2√2) = 2 + 4√2
# A↓ = (1 + 2√2) - (-3 - 2√2) = 4 + 4√2
# A  = max(3 + 2√2, 1 + 2√2) - min(1 - 2√2, -3 - 2√2) = 6 + 4√2
HAND_TARGET = np.tile([0.0, 10.0, 20.0], 4)
HAND_DIR = np.repeat(["+", "+", "-", "-"], 3)
HAND_RUN = np.repeat([1, 2, 1, 2], 3)
HAND_DEV = np.array([0, 2, 4, 2, 4, 2, -2, -1, 0, -4, -1, 2], dtype=float)


def test_hand_case_every_iso_figure():
    f = bidirectional_figures(HAND_TARGET, HAND_DIR, HAND_RUN, HAND_DEV)
    assert (f.n_targets, f.n_runs_up, f.n_runs_down) == (3, 2, 2)
    expected = {"E_up_um": 2, "E_down_um": 4, "E_um": 6, "M_um": 3, "B_um": 4, "B_mean_um": 10 / 3,
                "R_up_um": 4 * SQ2, "R_down_um": 4 * SQ2, "R_um": 4 + 4 * SQ2,
                "A_up_um": 2 + 4 * SQ2, "A_down_um": 4 + 4 * SQ2, "A_um": 6 + 4 * SQ2}
    for key, value in expected.items():
        assert getattr(f, key) == pytest.approx(value, abs=1e-12), key
    t = f.per_target
    np.testing.assert_allclose(t.target_mm, [0, 10, 20])
    np.testing.assert_allclose(t.mean_up_um, [1, 3, 3])
    np.testing.assert_allclose(t.mean_down_um, [-3, -1, 1])
    np.testing.assert_allclose(t.std_down_um, [SQ2, 0, SQ2], atol=1e-12)
    np.testing.assert_allclose(t.reversal_um, [4, 4, 2])
    np.testing.assert_allclose(t.R_um, [4 * SQ2 + 4, 2 * SQ2 + 4, 4 * SQ2 + 2])
    assert any("5 runs" in n for n in f.notes)  # 2 runs: indicative only


def test_hand_case_is_order_and_encoding_independent():
    """Shuffled captures, +1/-1 directions and targets off by 1e-9 mm give the same figures."""
    rng = np.random.default_rng(3)
    p = rng.permutation(HAND_DEV.size)
    sign = np.where(HAND_DIR == "+", 1, -1)
    jitter = rng.uniform(-1e-9, 1e-9, HAND_DEV.size)
    f = bidirectional_figures(HAND_TARGET[p] + jitter[p], sign[p], HAND_RUN[p], HAND_DEV[p])
    assert f.n_targets == 3
    assert f.R_um == pytest.approx(4 + 4 * SQ2)
    assert f.A_um == pytest.approx(6 + 4 * SQ2)


def test_invalid_captures_are_excluded():
    """A wild capture flagged invalid (and a NaN deviation) changes nothing."""
    t = np.concatenate([HAND_TARGET, [10.0, 20.0]])
    d = np.concatenate([HAND_DIR, ["+", "-"]])
    r = np.concatenate([HAND_RUN, [3, 3]])
    x = np.concatenate([HAND_DEV, [500.0, np.nan]])
    valid = np.concatenate([np.ones(HAND_DEV.size, bool), [False, True]])
    f = bidirectional_figures(t, d, r, x, valid)
    assert f.A_um == pytest.approx(6 + 4 * SQ2)
    assert f.n_runs_up == 2
    assert any("2 capture(s) left out" in n for n in f.notes)
    single = single_run_figures(t, x, valid)
    assert single.max_abs_deviation_um == 4.0


def test_frames_of_one_stop_are_one_approach():
    """Two frames per stop in one run are averaged: still one run, std undefined."""
    t = np.repeat([0.0, 1.0, 2.0], 2)
    f = bidirectional_figures(t, ["+"] * 6, [1] * 6, np.array([0, 2, 1, 1, 5, 7.0]))
    np.testing.assert_allclose(f.per_target.mean_up_um, [1, 1, 6])
    assert f.E_up_um == 5
    assert f.R_up_um is None and f.A_up_um is None
    assert any("One upward run only" in n for n in f.notes)


def test_one_run_both_directions_has_no_std_figures():
    keep = HAND_RUN == 1
    f = bidirectional_figures(HAND_TARGET[keep], HAND_DIR[keep], HAND_RUN[keep], HAND_DEV[keep])
    # x̄↑ = (0, 2, 4), x̄↓ = (-2, -1, 0): B_j = (2, 3, 4), mids = (-1, 0.5, 2)
    assert (f.B_um, f.B_mean_um, f.M_um, f.E_um) == (4, 3, 3, 6)
    assert f.R_um is None and f.A_um is None and f.R_up_um is None and f.A_down_um is None
    assert any("One upward run only" in n for n in f.notes)
    assert any("One downward run only" in n for n in f.notes)


def test_one_direction_has_no_bidirectional_figures():
    up = HAND_DIR == "+"
    f = bidirectional_figures(HAND_TARGET[up], HAND_DIR[up], HAND_RUN[up], HAND_DEV[up])
    assert f.B_um is None and f.M_um is None and f.R_um is None and f.A_um is None and f.E_down_um is None
    assert f.R_up_um == pytest.approx(4 * SQ2)
    assert f.A_up_um == pytest.approx(2 + 4 * SQ2)
    assert f.E_um == f.E_up_um == 2
    assert f.n_runs_down == 0
    assert any("Only upward" in n for n in f.notes)


def test_all_invalid_gives_nothing_to_compute():
    valid = np.zeros(HAND_DEV.size, bool)
    assert bidirectional_figures(HAND_TARGET, HAND_DIR, HAND_RUN, HAND_DEV, valid) is None
    s = single_run_figures(HAND_TARGET, HAND_DEV, valid)
    assert s.n_captures == 0 and s.scale_ppm is None and s.periodic_amplitude_um is None
    d = figures_for_session(HAND_TARGET, HAND_DIR, HAND_RUN, HAND_DEV, valid)
    assert d["iso230_2"] is None
    assert d["single_run"]["max_abs_deviation_um"] is None


def test_bad_input_is_a_one_line_input_error():
    with pytest.raises(InputError, match="direction"):
        direction_signs(["+", "x"])
    with pytest.raises(InputError, match="direction"):
        direction_signs([1, 0])
    with pytest.raises(InputError, match="deviation_um has 2 values"):
        bidirectional_figures([0.0, 1.0, 2.0], ["+"] * 3, [1] * 3, [0.0, 1.0])
    with pytest.raises(InputError, match="direction has 2 values"):
        figures_for_session([0.0, 1.0, 2.0], ["+"] * 2, [1] * 3, [0.0, 1.0, 2.0])
    with pytest.raises(InputError, match="sigma_um"):
        single_run_figures([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], sigma_um=[1.0, 0.0, 1.0])


# ---------------------------------------------------------------- single run


def test_single_run_hand_case():
    # measured = 0, 1.001, 2.000, 3.001 mm: steps 1.001, 0.999, 1.001 -> mean 1.000333 mm,
    # step deviations (+2/3, -4/3, +2/3) um -> var = (4/9 + 16/9 + 4/9)/2 = 4/3 -> std 1.1547 um.
    # LS slope of x = (0, 1, 0, 1) on t = (0, 1, 2, 3): Sxy / Sxx = 1 / 5 = 0.2 um/mm = 200 ppm.
    f = single_run_figures(np.arange(4.0), np.array([0.0, 1.0, 0.0, 1.0]))
    assert f.mean_step_mm == pytest.approx(1.0 + 1e-3 / 3)
    assert f.step_std_um == pytest.approx(math.sqrt(4 / 3))
    assert f.max_abs_deviation_um == 1.0 and f.deviation_span_um == 1.0
    assert f.scale_ppm == pytest.approx(200.0)
    assert f.n_captures == 4


def test_outlier_leaves_a_hole_not_a_double_step():
    t = np.arange(20.0)
    x = np.zeros(20)
    x[7] = 300.0
    valid = np.ones(20, bool)
    valid[7] = False
    f = single_run_figures(t, x, valid)
    assert f.mean_step_mm == pytest.approx(1.0) and f.step_std_um == pytest.approx(0.0)
    assert f.max_abs_deviation_um == 0.0


def test_scale_ppm_recovery_and_its_sigma():
    rng = np.random.default_rng(11)
    t = np.arange(400.0)
    x = 80.0 * 1e-3 * t + 5.0 + rng.normal(0, 0.5, t.size)  # 80 ppm = 0.08 um/mm
    f = single_run_figures(t, x)
    expected_sigma_ppm = 0.5 / math.sqrt(np.sum((t - t.mean()) ** 2)) * 1e3  # OLS slope sigma
    assert f.scale_sigma_ppm == pytest.approx(expected_sigma_ppm, rel=0.2)
    assert abs(f.scale_ppm - 80.0) < 4 * expected_sigma_ppm


def test_weighted_scale_fit_ignores_noisy_captures():
    """Every other capture is 50x noisier and says so in sigma_um: the weighted slope stays sharp."""
    rng = np.random.default_rng(12)
    t = np.arange(400.0)
    sigma = np.where(np.arange(400) % 2 == 0, 0.2, 10.0)
    x = 30.0 * 1e-3 * t + rng.normal(0, 1.0, t.size) * sigma
    weighted = single_run_figures(t, x, sigma_um=sigma)
    plain = single_run_figures(t, x)
    sharp = 0.2 / math.sqrt(np.sum((t[::2] - t[::2].mean()) ** 2)) * 1e3
    assert weighted.scale_sigma_ppm == pytest.approx(sharp, rel=0.25)
    assert abs(weighted.scale_ppm - 30.0) < 4 * sharp
    assert plain.scale_sigma_ppm > 10 * weighted.scale_sigma_ppm


def test_fft_recovers_a_5mm_lead_screw_pitch():
    rng = np.random.default_rng(5)
    t = np.arange(400.0)  # uniform 1 mm grid: FFT
    x = 40e-3 * t + 3.0 * np.sin(2 * np.pi * t / 5.0 + 0.7) + rng.normal(0, 0.5, t.size)
    f = single_run_figures(t, x)
    assert f.spectrum.method == "fft"
    assert f.periodic_period_mm == pytest.approx(5.0, rel=0.01)
    assert f.periodic_amplitude_um == pytest.approx(3.0, rel=0.05)
    assert f.scale_ppm == pytest.approx(40.0, abs=2.0)
    spec = f.to_dict()["spectrum"]
    assert len(spec["period_mm"]) == len(spec["amplitude_um"]) == 100  # periods of 4 steps and more: no alias
    assert min(spec["period_mm"]) == pytest.approx(4.0)
    assert spec["period_mm"][int(np.argmax(spec["amplitude_um"]))] == pytest.approx(5.0)


def test_lomb_scargle_recovers_an_off_bin_pitch_on_a_gappy_grid():
    """10 % of targets invalid, pitch 7.3 mm between FFT bins: Lomb-Scargle + refinement."""
    rng = np.random.default_rng(6)
    t = np.arange(400.0)
    x = -20e-3 * t + 2.0 * np.sin(2 * np.pi * t / 7.3 + 0.2) + rng.normal(0, 0.5, t.size)
    valid = rng.random(t.size) > 0.1
    x[~valid] = 1e3  # would dominate everything if used
    f = single_run_figures(t, x, valid)
    assert f.spectrum.method == "lomb-scargle"
    assert f.periodic_period_mm == pytest.approx(7.3, rel=0.01)
    assert f.periodic_amplitude_um == pytest.approx(2.0, rel=0.05)


def test_spectrum_needs_four_targets_and_ignores_the_longest_periods():
    assert deviation_spectrum(np.arange(3.0), np.zeros(3)) is None
    t = np.arange(100.0)
    # a bow (one cycle over the travel) larger than the 10 mm ripple: the peak is still the ripple
    y = 5.0 * np.sin(2 * np.pi * t / 100.0) + 1.0 * np.sin(2 * np.pi * t / 10.0)
    s = deviation_spectrum(t, y)
    assert s.peak_period_mm == pytest.approx(10.0, rel=0.01)
    assert s.peak_amplitude_um == pytest.approx(1.0, rel=0.05)


def test_a_period_the_plan_does_not_resolve_is_not_defined():
    """Issue 35: a 0-10 mm plan at 2 mm steps gave 3.45e+15 um at the Nyquist period, a min-step plan 240 um
    at 0.68 mm. A period needs 2 cycles in the travel, 4 samples in a cycle and no gap over half a cycle."""
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 10.0 + 1e-9, 2.0)
    f = single_run_figures(t, rng.normal(0, 1.0, t.size) + 5.0 * (-1.0) ** np.arange(t.size))
    assert f.periodic_amplitude_um is None and f.periodic_period_mm is None
    assert f.spectrum is not None and any("Periodic error not defined" in n for n in f.notes)
    # min-step: 10 steps of 2 um at three places, both ways; the jumps between places are no steps
    from lps_gui.core.planning.presets import min_step_plan_fields

    plan = np.asarray(min_step_plan_fields(0.0, 200.0)["targets_mm"])
    target = np.r_[plan, plan[::-1]]
    group = np.repeat([0, 1], plan.size)
    x = 2.0 * np.sin(2 * np.pi * target / 0.68) + rng.normal(0, 0.3, target.size)
    f = single_run_figures(target, x, group=group)
    assert f.periodic_amplitude_um is None and f.periodic_period_mm is None
    assert f.mean_step_mm == pytest.approx(0.002, abs=0.5e-3)
    assert f.step_std_um < 3.0  # the steps' own scatter (sine and noise), not the 100 mm jumps
    assert any("4 jump(s)" in n for n in f.notes)
    # the same sine on a plan that resolves it: 4 samples per period is enough
    t = np.arange(0.0, 60.0, 2.0)
    f = single_run_figures(t, 3.0 * np.sin(2 * np.pi * t / 8.0))
    assert f.periodic_period_mm == pytest.approx(8.0, rel=0.01) and f.periodic_amplitude_um == pytest.approx(3.0, rel=0.05)
    assert f.step_std_um > 0 and not any("jump" in n for n in f.notes)


def test_an_undefined_period_reads_not_defined_in_the_summary_and_csv():
    from lps_gui.io.results.document import summary_csv_rows, summary_figures

    single = {"n_captures": 6, "periodic_amplitude_um": None, "periodic_period_mm": None, "scale_ppm": 1.0}
    figs = {f.key: f for f in summary_figures({"figures": {"single_run": single}})}
    assert figs["periodic_amplitude"].unresolved.startswith("not defined")
    assert figs["periodic_period"].unresolved.startswith("not defined")
    rows = {r[0]: r[1] for r in summary_csv_rows({"figures": {"single_run": single}})}
    assert rows["periodic_amplitude"] is None and rows["periodic_period"] is None  # kept, empty: no number


# ---------------------------------------------------------------- session and specification


def test_session_figures_layout_and_json():
    rng = np.random.default_rng(8)
    targets = np.arange(0.0, 60.0, 2.0)
    parts = [(run, d) for run in (1, 2, 3) for d in ("+", "-")]
    t = np.concatenate([targets if d == "+" else targets[::-1] for _, d in parts])
    d = np.repeat([p[1] for p in parts], targets.size)
    r = np.repeat([p[0] for p in parts], targets.size)
    backlash_um = 6.0
    x = 50e-3 * t - np.where(d == "+", 0.5, -0.5) * backlash_um + rng.normal(0, 0.3, t.size)
    out = figures_for_session(t, d, r, x, sigma_um=np.full(t.size, 0.3))
    json.dumps(out, allow_nan=False)
    assert [(p["run"], p["direction"]) for p in out["per_run"]] == parts
    iso = out["iso230_2"]
    assert iso["B_mean_um"] == pytest.approx(-backlash_um, abs=0.5)
    assert iso["n_runs_up"] == iso["n_runs_down"] == 3
    single = out["single_run"]
    # one offset per run and direction: the backlash does not bias the slope nor fill the residuals
    assert single["scale_ppm"] == pytest.approx(50.0, abs=3.0)
    assert single["mean_step_mm"] == pytest.approx(2.0 * (1 + 50e-6), abs=2e-4)
    assert out["per_run"][0]["figures"]["scale_ppm"] == pytest.approx(50.0, abs=10.0)


def test_session_with_one_run_one_direction_has_no_iso_figures():
    t = np.arange(10.0)
    out = figures_for_session(t, ["+"] * 10, [1] * 10, np.zeros(10))
    assert out["iso230_2"] is None
    assert len(out["per_run"]) == 1 and out["single_run"]["n_captures"] == 10


def test_check_specification_reads_plus_minus_limits_as_half_bands():
    figures = figures_for_session(HAND_TARGET, HAND_DIR, HAND_RUN, HAND_DEV)
    figures["straightness_um_max"] = 30.0
    rows = check_specification(figures, {"accuracy_um": 20, "repeatability_um": 4, "straightness_um": 38})
    by = {r["name"]: r for r in rows}
    assert by["Positional accuracy"]["measured"] == pytest.approx((6 + 4 * SQ2) / 2)  # A/2 = 5.83
    assert by["Positional accuracy"]["passed"] is True
    assert by["Repeatability"]["measured"] == pytest.approx((4 + 4 * SQ2) / 2)  # R/2 = 4.83 > 4
    assert by["Repeatability"]["passed"] is False
    assert by["Straight-line accuracy"]["passed"] is True
    band = {r["name"]: r for r in check_specification(figures, {"accuracy_um": 10, "limits": "band"})}
    assert band["Positional accuracy"]["measured"] == pytest.approx(6 + 4 * SQ2)
    assert band["Positional accuracy"]["passed"] is False


def test_check_specification_with_one_run_uses_the_deviation_span():
    t = np.arange(10.0)
    x = np.linspace(-3.0, 5.0, 10)
    figures = figures_for_session(t, ["+"] * 10, [1] * 10, x)
    by = {r["name"]: r for r in check_specification(figures, {"accuracy_um": 3.5, "repeatability_um": 5,
                                                               "straightness_um": 38})}
    assert by["Positional accuracy"]["measured"] == pytest.approx(4.0)  # span 8 / 2
    assert by["Positional accuracy"]["passed"] is False
    assert by["Repeatability"]["passed"] is None and by["Repeatability"]["measured"] is None
    assert by["Straight-line accuracy"]["passed"] is None
    del figures["single_run"]["deviation_span_um"]  # results written without the span: 2 max|x| / 2
    assert check_specification(figures, {"accuracy_um": 6})[0]["measured"] == pytest.approx(5.0)
    with pytest.raises(InputError, match="accuracy_um"):
        check_specification(figures, {"accuracy_um": "twenty"})


def test_repeated_positions_are_merged_into_their_mean():
    """Two runs over one grid: the pooled spectrum is the spectrum of the per-target means (FFT)."""
    rng = np.random.default_rng(9)
    t = np.arange(200.0)
    a, b = rng.normal(0, 1, 200), rng.normal(0, 1, 200)
    pooled = deviation_spectrum(np.r_[t, t[::-1]], np.r_[a, b[::-1]])
    mean = deviation_spectrum(t, (a + b) / 2)
    assert pooled.method == mean.method == "fft"
    np.testing.assert_allclose(pooled.amplitude_um, mean.amplitude_um, atol=1e-12)


def test_session_figures_recover_the_stage_error_model():
    """Closed loop on the simulator's truth: scale, lead-screw pitch, backlash and repeatability."""
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.truth.stage_errors import StageErrorModel

    model = StageErrorModel(scale_ppm=60.0, periodic_um=2.5, pitch_mm=4.0, periodic_phase_rad=0.3,
                            backlash_um=8.0, repeatability_um=0.4)
    stops = list(Plan(start_mm=0.0, stop_mm=200.0, step_mm=1.0, directions="both", runs=5).stops())
    target = np.array([s.target_mm for s in stops])
    direction = np.array([s.direction for s in stops])
    run = np.array([s.run for s in stops])
    true_mm = model.true_pose(target, np.where(direction == "+", 1.0, -1.0), np.random.default_rng(21)).axis_mm
    deviation_um = (true_mm - target) * 1e3
    deviation_um -= deviation_um[0]  # SPEC 5: offset zero at the first capture
    out = figures_for_session(target, direction, run, deviation_um)
    single, iso = out["single_run"], out["iso230_2"]
    assert single["scale_ppm"] == pytest.approx(60.0, abs=1.0)
    assert single["periodic_period_mm"] == pytest.approx(4.0, rel=0.01)
    assert single["periodic_amplitude_um"] == pytest.approx(2.5, rel=0.05)
    assert single["mean_step_mm"] == pytest.approx(1.0 + 60e-6, abs=2e-5)
    assert iso["n_runs_up"] == iso["n_runs_down"] == 5
    assert iso["B_mean_um"] == pytest.approx(-8.0, abs=0.2)  # up stops short by b/2, down overshoots by b/2
    std = np.r_[iso["per_target"]["std_up_um"], iso["per_target"]["std_down_um"]]
    assert np.sqrt(np.mean(std**2)) == pytest.approx(0.4, rel=0.1)  # pooled s: the model's repeatability
    # systematic deviation E: the scale line over 200 mm plus the ripple plus the backlash, within noise
    e_truth = np.ptp(np.r_[model.positioning_error_um(target, 1.0), model.positioning_error_um(target, -1.0)])
    assert iso["E_um"] == pytest.approx(e_truth, abs=5 * 0.4 / np.sqrt(5))
    assert len(out["per_run"]) == 10
