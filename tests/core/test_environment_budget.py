"""Environment (thermal scale) and the GUM uncertainty budget, as pure math."""
import math

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.metrology.environment import Environment, corrected_board, thermal_scale
from lps_gui.core.metrology.uncertainty_budget import BudgetInputs, budget_rows, combine, figure_uncertainties
from lps_gui.errors import InputError


def test_warm_board_has_larger_squares():
    env = Environment.from_dict({"board_temperature_c": 23, "board_cte_ppm_per_k": 23})
    assert thermal_scale(env) == pytest.approx(1 + 69e-6)
    assert corrected_board(Board(9, 6, 20.0), env).square_mm == pytest.approx(20.0 * (1 + 69e-6))
    cold = Environment.from_dict({"board_temperature_c": 18, "board_cte_ppm_per_k": 10})
    assert thermal_scale(cold) == pytest.approx(1 - 20e-6)
    assert thermal_scale(Environment.from_dict({"board_temperature_c": 30})) == 1.0  # no coefficient, no correction


@pytest.mark.parametrize("bad, needle", [({"board_temperature_c": "warm"}, "board_temperature_c"),
                                          ({"board_temp": 20}, "unknown key"),
                                          ({"square_mm_uncertainty_um": -1}, "negative"),
                                          ({"stage_temperature_c": 293.15}, "Celsius")])
def test_bad_environment_is_one_line_error(bad, needle):
    with pytest.raises(InputError, match=needle):
        Environment.from_dict(bad)


def _inputs(**kw):
    n = 40
    rng = np.random.default_rng(1)
    base = dict(travel_mm=100.0, square_mm=10.0, sigma_px=0.1, sigma_um=np.full(n, 0.6), sigma_total_um=np.full(n, 1.0),
                abbe_lever_mm=(600.0, 50.0), tilt_urad=rng.normal(0, 5, (n, 2)), tilt_sigma_urad=np.full((n, 2), 5.0))
    base.update(kw)
    return BudgetInputs(**base)


def test_budget_rows_and_expanded_uncertainty():
    env = Environment.from_dict({"board_temperature_c": 23, "board_cte_ppm_per_k": 23, "square_mm_uncertainty_um": 0.5,
                                 "stage_temperature_c": 21, "stage_cte_ppm_per_k": 12})
    rows = {r.source: r for r in budget_rows(_inputs(), env)}
    assert set(rows) >= {"corner noise", "reference view noise", "intrinsics", "board square size",
                         "board temperature", "board expansion coefficient", "stage temperature", "Abbe offset"}
    assert rows["corner noise"].contribution_um == pytest.approx(0.6 / math.sqrt(2))
    assert rows["intrinsics"].contribution_um == pytest.approx(0.8)
    assert rows["board square size"].contribution_um == pytest.approx(10 * 0.5)  # 10 squares over 100 mm
    assert rows["board temperature"].contribution_um == pytest.approx(23 * 100e-3 * 0.5)  # 0.5 K default
    assert rows["board expansion coefficient"].contribution_um == pytest.approx(3 * 100e-3 * 2.3)  # 10 % of 23
    assert rows["stage temperature"].contribution_um == pytest.approx(12 * 100e-3 / math.sqrt(3))
    for r in rows.values():
        if r.contribution_um is not None and r.value is not None:
            assert r.contribution_um == pytest.approx(abs(r.sensitivity) * r.value)
    unc = combine(list(rows.values()))
    u_c = math.sqrt(sum(r.contribution_um ** 2 for r in rows.values()))
    assert unc["expanded_k2_um"] == pytest.approx(2 * u_c) and unc["coverage_factor"] == 2
    figs = figure_uncertainties(unc, {"single_run": {"scale_sigma_total_ppm": 1.0}}, 100.0)
    assert figs["A_um"] == unc["expanded_k2_um"]
    assert figs["R_um"] < figs["A_um"]  # scale and temperature cancel at one target
    assert figs["scale_ppm"] > 2 * 50  # the square's 0.5 um per 10 mm is 50 ppm


def test_tilt_within_noise_gives_no_abbe_term_and_missing_sources_are_listed():
    n = 200
    rng = np.random.default_rng(2)
    rows = {r.source: r for r in budget_rows(_inputs(tilt_urad=rng.normal(0, 5, (n, 2)),
                                                     tilt_sigma_urad=np.full((n, 2), 5.0),
                                                     sigma_um=np.full(n, 0.6), sigma_total_um=np.full(n, 1.0)),
                                             Environment())}
    assert rows["Abbe offset"].contribution_um < 600e-3 * 2.0  # the noise alone is not an Abbe error
    # a real pitch of 10 urad amplitude along the travel is found through the noise, over the board distance
    t = np.linspace(0, 100, n)
    pitch = 10.0 * np.sin(2 * np.pi * t / 200.0)  # smooth, RMS 7.07 urad
    tilt = np.stack([pitch + rng.normal(0, 5, n), rng.normal(0, 5, n)], axis=1)
    abbe = {r.source: r for r in budget_rows(_inputs(tilt_urad=tilt, tilt_sigma_urad=np.full((n, 2), 5.0), target_mm=t,
                                                     sigma_um=np.full(n, 0.6), sigma_total_um=np.full(n, 1.0)),
                                             Environment())}["Abbe offset"]
    assert abbe.contribution_um == pytest.approx(0.6 * np.std(pitch), rel=0.25)
    unc = combine(list(rows.values()))
    assert {"board square size", "board temperature", "stage temperature"} <= set(unc["not_in_u"])


def test_periodic_amplitude_uncertainty_matches_a_monte_carlo_fit():
    """U of a fitted sinusoid's amplitude from noise: check sqrt(2/n) against simulated fits."""
    rng = np.random.default_rng(7)
    n, sigma = 100, 0.5
    x = np.linspace(0, 100, n)
    A = np.stack([np.sin(2 * np.pi * x / 5), np.cos(2 * np.pi * x / 5)], axis=1)
    amps = []
    for _ in range(400):
        y = 3.0 * np.sin(2 * np.pi * x / 5) + rng.normal(0, sigma, n)
        c = np.linalg.lstsq(A, y, rcond=None)[0]
        amps.append(np.hypot(*c))
    unc = {"coverage_factor": 2.0, "expanded_k2_um": 1.0, "noise_standard_um": sigma * math.sqrt(2)}
    figures = {"single_run": {"periodic_amplitude_um": float(np.mean(amps))}}
    U = figure_uncertainties(unc, figures, 100.0, n_views=n)["periodic_amplitude_um"]
    assert U / 2 == pytest.approx(np.std(amps), rel=0.15)
    # a periodic error the plan does not define (no amplitude) has no U either
    assert figure_uncertainties(unc, {"single_run": {}}, 100.0, n_views=n)["periodic_amplitude_um"] is None


def test_a_tilt_curve_within_the_noise_gives_no_abbe_term():
    """A quick demo: 48 views, per-view pitch/yaw sigma 500 urad, no tilt at all; the cubic fit's noise is not a tilt."""
    from lps_gui.core.metrology.uncertainty_budget import smooth_tilt_spread_urad

    n = 48
    t = np.repeat(np.linspace(0, 22, 12), 4)
    found = 0
    for seed in range(20):
        tilt = np.random.default_rng(seed).normal(0, 500.0, (n, 2))
        found += int(np.count_nonzero(smooth_tilt_spread_urad(tilt, np.full((n, 2), 500.0), t)))
    assert found <= 2  # of 40 angle curves (without the significance rule 11 were counted)
    tilt = np.stack([300.0 * (t / 22.0) ** 2 + np.random.default_rng(1).normal(0, 50.0, n), np.zeros(n)], axis=1)
    assert smooth_tilt_spread_urad(tilt, np.full((n, 2), 50.0), t)[0] == pytest.approx(np.std(300.0 * (t / 22.0) ** 2),
                                                                                       rel=0.15)


def test_abbe_term_only_for_angles_the_error_motions_resolve_and_the_lens_row():
    """Issue 35: a smooth pitch that the error motions do not resolve (a lens misfit could fake it) is no Abbe term;
    the positions' lens-model share is its own row, not the intrinsics'."""
    n = 40
    t = np.linspace(0, 100, n)
    tilt = np.stack([10.0 * np.sin(2 * np.pi * t / 200.0), np.zeros(n)], axis=1)
    kw = dict(tilt_urad=tilt, tilt_sigma_urad=np.full((n, 2), 0.5), target_mm=t)
    resolved = {r.source: r for r in budget_rows(_inputs(**kw, tilt_resolved=(True, False)), Environment())}
    unresolved = {r.source: r for r in budget_rows(_inputs(**kw, tilt_resolved=(False, False)), Environment())}
    assert resolved["Abbe offset"].contribution_um > 1.0  # about 0.6 um/urad x the smooth pitch
    assert unresolved["Abbe offset"].contribution_um == 0.0 and "pitch (EBX) not resolved: no term" in \
        unresolved["Abbe offset"].note
    lens = {r.source: r for r in budget_rows(_inputs(sigma_total_um=np.full(n, np.hypot(1.0, 2.0)),
                                                     sigma_lens_um=np.full(n, 2.0)), Environment())}
    assert lens["lens model"].contribution_um == pytest.approx(2.0)
    assert lens["intrinsics"].contribution_um == pytest.approx(np.sqrt(1.0 - 0.36))


def test_the_abbe_row_is_shown_but_not_in_u():
    """Issue 35: the positions are the displacement at the board plane, so a resolved pitch's Abbe row (what the
    camera centre's displacement would differ by) is in the table and not in U of A, E, M or max |deviation|."""
    n = 40
    t = np.linspace(0, 100, n)
    tilt = np.stack([1000.0 * np.sin(2 * np.pi * t / 200.0), np.zeros(n)], axis=1)
    rows = budget_rows(_inputs(tilt_urad=tilt, tilt_sigma_urad=np.full((n, 2), 0.5), target_mm=t,
                               tilt_resolved=(True, False)), Environment())
    abbe = next(r for r in rows if r.source == "Abbe offset")
    assert abbe.contribution_um > 100.0 and "not in U" in abbe.note  # the smooth pitch x 600 mm
    unc = combine(rows)
    others = [r.contribution_um for r in rows if r.contribution_um is not None and r.source != "Abbe offset"]
    assert unc["expanded_k2_um"] == pytest.approx(2 * math.sqrt(sum(c * c for c in others)))
    assert unc["expanded_k2_um"] < 10.0
    corr = {"iso230_2": {"noise_correction": {"A_um": {"u_noise": 1.0}}}}
    assert figure_uncertainties(unc, corr, 100.0)["A_um"] < 10.0
