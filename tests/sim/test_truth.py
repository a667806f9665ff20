"""sim/truth: truth.jsonl pruned, folded and read by one rule; the one reduction against a measurement."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.sim.truth import (
    TRUTH_FILE,
    append_truth,
    centred,
    finalize_truth,
    prune_truth,
    read_truth,
    reduce_truth,
    residual_from_line,
    session_truth,
    true_deviation_um,
    truth_comparison,
)
from tests.capture.helpers import tiny_spec


def test_prune_drops_unlisted_duplicate_and_torn_lines(tmp_path):
    spec = tiny_spec(Plan(start_mm=0.0, stop_mm=4.0, step_mm=1.0))
    session = Session.create(tmp_path / "s", spec.rig.board, spec.plan, truth={"simulated": True})
    for i in range(2):
        session.append(CaptureRecord(i, 1, "+", float(i), float(i), f"images/{i:06d}.png", "x", 0.0))
    for i, axis in ((0, 0.001), (1, 1.002), (1, 1.002), (2, 2.0)):  # 1 twice, 2 never listed
        append_truth(session, i, {"axis_mm": axis, "straightness_um": [0, 0], "angles_urad": [0, 0, 0]})
    with open(session.folder / TRUTH_FILE, "a") as f:
        f.write('{"index": 3, "axis')  # torn by a kill
    prune_truth(session)
    lines = [json.loads(line) for line in (session.folder / TRUTH_FILE).read_text().splitlines()]
    assert [d["index"] for d in lines] == [0, 1]
    finalize_truth(session)
    truth = Session.open(session.folder).truth
    assert truth["simulated"] and truth["index"] == [0, 1]
    assert truth["axis_mm"] == [0.001, 1.002]
    assert truth["positions_mm"] == [0.0, 1.002 - 0.001]
    assert set(read_truth(session)) == {0, 1}


def test_session_truth_reads_the_sidecar_by_the_same_rule(tmp_path):
    """A duplicated line (resume) counts once, the last one; the arrays come sorted by capture index."""
    spec = tiny_spec(Plan(start_mm=0.0, stop_mm=4.0, step_mm=1.0))
    session = Session.create(tmp_path / "s", spec.rig.board, spec.plan, truth={"simulated": True, "bumped_views": [1]})
    for i, axis in ((1, 1.5), (0, 0.0), (1, 1.002)):
        append_truth(session, i, {"axis_mm": axis, "straightness_um": [i, 0], "angles_urad": [0, 0, i]})
    truth = session_truth(session)
    assert truth["index"].tolist() == [0, 1] and truth["axis_mm"].tolist() == [0.0, 1.002]
    assert truth["straightness_um"].shape == (2, 2) and truth["angles_urad"][1, 2] == 1
    assert truth["bumped_views"] == [1] and "plane_mm" not in truth  # no rig geometry recorded


def test_reduce_truth_is_relative_to_the_reference_capture_in_any_dimension():
    rng = np.random.default_rng(0)
    true = np.cumsum(rng.normal(1.0, 0.01, size=(6, 2)), axis=0)  # a planar path, mm
    err_um = rng.normal(0, 2.0, size=(6, 2))
    measured = true + 1e-3 * err_um + np.array([5.0, -3.0])  # any origin
    compared = np.array([True, True, True, False, True, True])
    red = reduce_truth(measured, true, 1, compared, sigma_um=np.full((6, 2), 2.0))
    expected = err_um - err_um[1]
    assert np.allclose(red.error_um, expected) and np.all(red.error_um[1] == 0)
    lengths = np.linalg.norm(expected[compared], axis=1)
    assert red.rms_um == pytest.approx(np.sqrt(np.mean(lengths**2)))
    assert red.max_abs_um == pytest.approx(lengths.max())
    others = compared & (np.arange(6) != 1)
    assert red.z_mean_square == pytest.approx(np.mean((expected[others] / 2.0) ** 2))
    # one dimension is the same computation on a column
    one = reduce_truth(measured[:, 0], true[:, 0], 1, compared)
    assert np.allclose(one.error_um[:, 0], expected[:, 0]) and one.z_mean_square is None


def test_truth_helpers_share_the_reference():
    target = np.array([0.0, 2.0, 4.0, 6.0])
    true = target + np.array([0.001, 0.0025, 0.004, 0.0041])
    assert np.allclose(true_deviation_um(true, target, 0), [0.0, 1.5, 3.0, 3.1])
    values = np.c_[1.0 + 0.5 * target, -target]
    assert np.allclose(residual_from_line(values, target, np.ones(4, bool)), 0.0, atol=1e-12)
    assert np.allclose(centred(np.c_[target], np.array([True, True, False, False])), np.c_[target - 1.0])


def test_the_per_stop_z_scores_the_drawn_sigma_not_the_noise_alone():
    """Issue 35: the truth check's per-stop mean (error/sigma)^2 is against the sigma the bands draw
    (``sigma_total_um``: noise, intrinsics, lens model), computed once: the estimate's own, or the one the error
    motions drew with the lens misfit folded in, given (the estimate's mean sigma stays its own)."""
    from types import SimpleNamespace

    K = 5
    target = np.arange(K, dtype=float)
    err_mm = np.array([0.0, 2e-3, -2e-3, 2e-3, -2e-3])  # 2 um off truth at every stop but the reference
    est = SimpleNamespace(D=1, reference_view=0, used=np.ones(K, bool), outlier=np.zeros(K, bool),
                          state=SimpleNamespace(s=target + err_mm), sigma_s_mm=np.full(K, 1e-3),
                          sigma_total_mm=np.full(K, 2e-3), board_plane=None)
    obs = SimpleNamespace(index=np.arange(K), target_mm=target)
    truth = {"index": list(range(K)), "axis_mm": target.tolist(), "plane_mm": target.tolist()}
    positions = [{"deviation_um": 1e3 * e, "sigma_total_um": 2.0} for e in err_mm]
    tc, rows = truth_comparison(obs, est, truth, positions)
    assert tc["z_mean_square"] == pytest.approx(1.0) and tc["board_plane_z_mean_square"] == pytest.approx(1.0)
    drawn = np.full(K, 4.0)  # the lens misfit folded in
    folded, folded_rows = truth_comparison(obs, est, truth, [{**r, "sigma_total_um": 4.0} for r in positions],
                                           drawn_sigma_um=drawn)
    assert folded["z_mean_square"] == pytest.approx(0.25) and folded["board_plane_z_mean_square"] == pytest.approx(0.25)
    assert folded["mean_sigma_um"] == tc["mean_sigma_um"] == pytest.approx(2.0)
    assert [r["truth_deviation_um"] for r in folded_rows] == [r["truth_deviation_um"] for r in rows]
