"""Plot definitions against the numbers put into the results dict and the simulator's truth."""
from __future__ import annotations

import numpy as np

from lps_gui.core.truth.simulate import small_spec
from lps_gui.report.figures.plots import (
    FIGURE_KEYS,
    figure_by_key,
    figures_from_results,
    per_target_stats,
    truth_columns,
)
from tests.report.conftest import make_results


def test_every_figure_in_report_order_with_units():
    results, truth = make_results()
    figs = figures_from_results(results, truth)
    assert tuple(f.key for f in figs) == FIGURE_KEYS
    for f in figs:
        assert "[" in f.x_label and "]" in f.x_label, f.key
        assert "[" in f.y_label and "]" in f.y_label, f.key
        assert not f.is_empty(), f.key


def test_deviation_band_is_mean_plus_minus_two_std_over_runs_without_outliers():
    results, truth = make_results(runs=3)
    dev = figure_by_key(figures_from_results(results, truth), "deviation")
    mean_fwd = next(s for s in dev.series if s.label.startswith("mean") and "forward" in s.label)
    rows = [r for r in results["positions"] if r["direction"] == "+" and not r["outlier"]]
    for target, y, lo, hi in zip(mean_fwd.x, mean_fwd.y, mean_fwd.band_low, mean_fwd.band_high):
        vals = np.array([r["deviation_um"] for r in rows if r["target_mm"] == target])
        assert np.isclose(y, vals.mean())
        assert np.isclose(hi - y, 2 * vals.std(ddof=1)) and np.isclose(y - lo, 2 * vals.std(ddof=1))


def test_single_run_band_is_the_total_sigma_and_outlier_is_marked():
    """The band draws sigma_total_um (0.8: noise, intrinsics, lens model), not the noise alone (0.5): issue 35."""
    results, truth = make_results(runs=1, directions="+")
    dev = figure_by_key(figures_from_results(results, truth), "deviation")
    s = dev.series[0]
    assert np.allclose(s.band_high - s.y, 2 * 0.8)
    assert "intrinsics" in dev.notes
    assert s.marked is not None and s.marked.sum() == 1 and s.marked[5]
    res = figure_by_key(figures_from_results(results), "residuals")
    assert res.series[0].marked[5] and res.series[0].marked.sum() == 1


def test_truth_deviation_follows_the_stage_error_model():
    """Truth drawn beside the measurement is the simulator's positioning error (offset at the first capture)."""
    results, truth = make_results(runs=2)
    spec = small_spec(seed=3, views=12, directions="both", runs=2)
    t = truth_columns(results, truth)
    target = np.array([r["target_mm"] for r in results["positions"]])
    direction = np.array([1.0 if r["direction"] == "+" else -1.0 for r in results["positions"]])
    e = spec.rig.errors.positioning_error_um(target, direction)
    expected = e - e[0]
    # repeatability noise (1 um) is in the truth but not in the systematic model
    assert np.max(np.abs(t["deviation_um"] - expected)) < 5.0
    assert np.corrcoef(t["deviation_um"], expected)[0, 1] > 0.9


def test_truth_straightness_has_the_fitted_line_removed():
    results, truth = make_results()
    axis = np.asarray(truth["positions_mm"])
    truth = dict(truth, straightness_um=np.stack([3.0 + 0.5 * axis, -2.0 * axis], axis=1).tolist(),
                 angles_urad=np.tile([10.0, 20.0, 30.0], (axis.size, 1)).tolist())
    t = truth_columns(results, truth)
    # the line is fitted against the target (as the estimate's): what is left is slope x positioning error
    for key in ("straightness_um_1", "straightness_um_2"):
        assert np.max(np.abs(t[key])) < 0.05, key
    for key in ("roll_urad", "pitch_urad", "yaw_urad"):
        assert np.max(np.abs(t[key])) < 1e-9, key


def test_no_truth_for_a_real_session():
    results, _ = make_results()
    figs = figures_from_results(results, None)
    assert not any(s.dashed for f in figs for s in f.series)


def test_per_target_stats_counts_only_kept_finite_values():
    t = np.array([0.0, 1.0, 0.0, 1.0, 0.0])
    v = np.array([1.0, 2.0, 3.0, np.nan, 100.0])
    keep = np.array([True, True, True, True, False])
    targets, mean, std, count = per_target_stats(t, v, keep)
    assert targets.tolist() == [0.0, 1.0] and mean.tolist() == [2.0, 2.0] and count.tolist() == [2, 1]
    assert np.isclose(std[0], np.std([1.0, 3.0], ddof=1)) and np.isnan(std[1])


def test_spectrum_comes_from_the_results_figures():
    results, _ = make_results()
    spectrum = results["figures"]["single_run"]["spectrum"]
    spec = figure_by_key(figures_from_results(results), "spectrum")
    s = spec.series[0]
    order = np.argsort(spectrum["period_mm"])
    assert np.allclose(s.x, np.asarray(spectrum["period_mm"])[order])
    assert np.allclose(s.y, np.asarray(spectrum["amplitude_um"])[order])
    assert spec.x_log


def test_truth_beside_each_position_wins_over_the_session_record():
    results, truth = make_results()
    for i, r in enumerate(results["positions"]):
        r.update({"truth_deviation_um": float(i), "truth_straightness_um_1": 1.0, "truth_straightness_um_2": 2.0,
                  "truth_roll_urad": 3.0, "truth_pitch_urad": 4.0, "truth_yaw_urad": None})
    t = truth_columns(results, truth)
    assert t["deviation_um"].tolist() == list(range(len(results["positions"])))
    assert np.all(t["roll_urad"] == 3.0) and np.all(np.isnan(t["yaw_urad"]))


def test_repeated_stops_of_one_run_are_not_called_runs():
    """Issue 37: a min-step session's legend said "over 8 runs" while its ISO table said "runs 1/1"."""
    import numpy as np

    from lps_gui.report.figures.plots import deviation_figure

    n = 16
    cols = {"target_mm": np.repeat([0.0, 1.0], 8), "deviation_um": np.linspace(0, 1, n), "outlier": np.zeros(n, bool),
            "direction": np.array(["+"] * n), "sigma_um": np.full(n, 0.1), "run": np.ones(n)}
    fig = deviation_figure(cols, None)
    assert "8 runs" not in fig.notes and "(1 run)" in fig.notes
    assert not any(s.label.startswith("runs") for s in fig.series)
    cols["run"] = np.tile(np.arange(1.0, 9.0), 2)  # eight real runs: still "runs"
    assert "over 8 runs" in deviation_figure(cols, None).notes


def test_the_truth_beside_the_positions_is_at_the_board_plane_where_they_are_measured():
    """Issue 37: page 6 plotted the camera-centre truth against positions measured at the board plane."""
    import numpy as np

    from lps_gui.report.figures.plots import figure_by_key, figures_from_results
    from lps_gui.report.pages.summary import position_table
    from tests.report.conftest import make_results

    results, _ = make_results(runs=1, directions="+")
    for k, p in enumerate(results["positions"]):
        p["truth_deviation_um"] = 100.0 + k  # camera centre: an Abbe term away
        p["truth_plane_deviation_um"] = float(k)  # at the board plane, where the positions are measured
    fig = figure_by_key(figures_from_results(results), "deviation")
    truth = [s for s in fig.series if s.label.startswith("truth")]
    assert truth and np.nanmax(np.abs(truth[0].y)) < 50.0
    header, body, _ = position_table(results)
    assert "truth dev.\nboard pl." in header
    col = header.index("truth dev.\nboard pl.")
    assert body[3][col] == "3.00"
