"""A results dict built from simulator truth plus known noise, shaped like results.json.

The report is tested against numbers we put in, so the estimator need not run
(and a report bug cannot hide behind an estimator bug).
"""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.metrology.environment import Environment, thermal_record
from lps_gui.core.metrology.iso230 import figures_for_session
from lps_gui.core.truth.simulate import small_spec, true_views
from lps_gui.pipeline.results.uncertainty import uncertainty_of

ENVIRONMENT = {"board_temperature_c": 21.0, "board_cte_ppm_per_k": 10.0, "square_mm_uncertainty_um": 0.2}


def make_results(runs: int = 2, directions: str = "both", views: int = 12, seed: int = 3) -> tuple[dict, dict]:
    """(results dict, session truth) for a small bidirectional simulated session."""
    spec = small_spec(seed=seed, views=views, directions=directions, runs=runs)
    rng = np.random.default_rng(seed)
    stops, _R, _t, truth = true_views(spec, rng)
    s_true = np.asarray(truth["positions_mm"])
    noise_um = rng.normal(0.0, 0.5, size=s_true.size)
    target = np.array([s.target_mm for s in stops])
    straight = np.asarray(truth["straightness_um"])
    angles = np.asarray(truth["angles_urad"])
    positions = []
    for i, s in enumerate(stops):
        measured = s_true[i] + noise_um[i] * 1e-3 + target[0]
        positions.append({
            "index": s.index, "run": s.run, "direction": s.direction, "target_mm": s.target_mm,
            "measured_mm": measured, "deviation_um": (measured - s.target_mm) * 1000.0,
            "sigma_um": 0.5, "sigma_total_um": 0.8, "rms_px": 0.2 + 0.01 * (i % 3), "n_corners": 54,
            "outlier": i == 5, "outlier_reason": "reprojection" if i == 5 else "",
            "straightness_um_1": straight[i, 0], "straightness_um_2": straight[i, 1],
            "straightness_sigma_um_1": 0.3, "straightness_sigma_um_2": 0.9,
            "roll_urad": angles[i, 0], "pitch_urad": angles[i, 1], "yaw_urad": angles[i, 2],
            "roll_sigma_urad": 2.0, "pitch_sigma_urad": 3.0, "yaw_sigma_urad": 3.0,
            "file": f"images/{i:05d}.png",
        })
    dev = np.array([p["deviation_um"] for p in positions])
    outlier = np.array([p["outlier"] for p in positions])
    direction = np.array([1 if s.direction == "+" else -1 for s in stops])
    run = np.array([s.run for s in stops])
    figures = figures_for_session(target, direction, run, dev, valid=~outlier, sigma_um=np.full(dev.shape, 0.5))
    figures["straightness_um_max"] = float(np.ptp(straight[~outlier], axis=0).max())
    results = {
        "format": "lps-results/1",
        "software": {"name": "lps-calib", "version": "test"},
        "created": "2026-11-23T10:00:00+0000",
        "method": "joint",
        "settings": {"robust": False, "outlier_k": 5.0},
        "inputs": {"session": "sim", "sha256": {"session.json": "ab" * 32}, "intrinsics_source": "session"},
        "board": {"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20.0},
        "intrinsics": {"image_size": [640, 480], "camera_matrix": [[600, 0, 322], [0, 600, 238], [0, 0, 1]],
                       "dist": [-0.12, 0.08, 0.0005, -0.0003, -0.01],
                       "std": {"fx": 0.5, "fy": 0.5, "cx": 0.4, "cy": 0.4, "k1": 0.001}},
        "parameters": {"sigma_px": 0.2, "rms_px": 0.21, "n_views": len(stops), "n_used": len(stops) - 1,
                       "n_observations": 54 * len(stops), "dof": 1000, "iterations": 6, "converged": True},
        "positions": positions,
        "figures": figures,
        "flags": [{"index": 5, "kind": "reprojection", "message": "view 5: RMS 2.1 px > 5 robust sigma"}],
        "timings_s": {"total": 1.0},
        "truth_comparison": {"position_rms_error_um": 0.5},
    }
    env = ENVIRONMENT
    results["environment"] = thermal_record(Board(9, 6, 20.0), Environment.from_dict(env))
    results["uncertainty"] = uncertainty_of(results, Environment.from_dict(env), 20.0)
    return results, truth


@pytest.fixture
def results_and_truth():
    return make_results()


def with_unresolved_extremes(results: dict) -> dict:
    """The results with straightness, image rotation and angles figures as `lps demo --quick` gives them.

    Every one is "not resolved" with a wide noise bound: the longest cells of the
    report's "Measured figures" table (the demo's page 2 cut them before the layout check).
    """
    figs = results["figures"]
    figs["straightness"] = {"basis": "board plane, constant orientation (SPEC 11)",
                            "v1": {"span_um": 3.53, "sigma_um": 1.33, "noise_span_um": 7.57, "n_targets": 12,
                                   "resolved": False},
                            "v2": {"span_um": 29.3, "sigma_um": 10.8, "noise_span_um": 61.4, "n_targets": 12,
                                   "resolved": False}}
    figs["image_rotation"] = {"span_urad": 63.9, "sigma_urad": 22.1, "noise_span_urad": 126.3, "n_targets": 12,
                              "resolved": False}
    figs["angles_resolution"] = {name: {"max_abs_urad": v, "noise_max_abs_urad": n, "resolved": False}
                                 for name, v, n in (("roll", 1454.3, 2320.5), ("pitch", 704.5, 1671.2),
                                                    ("yaw", 88.2, 168.4))}
    figs["straightness"]["v1"].update(span_um=12.5, resolved=True)  # one resolved p-v: printed with its U
    env = Environment.from_dict(ENVIRONMENT)
    results["uncertainty"] = uncertainty_of(results, env, 20.0)  # the per-figure U of the figures just added
    return results


def write_session(folder, results: dict, truth: dict | None = None, spec: dict | None = None):
    """A session folder holding session.json (truth, stage spec) and results.json: what the reports read."""
    import json

    folder.mkdir(parents=True)
    meta = {"format": "lps-session/1", "camera": {"name": "simulated"}, "stage": {"name": "sim"}}
    if truth:
        meta["truth"] = truth
    if spec:
        meta["stage_spec"] = spec
    (folder / "session.json").write_text(json.dumps(meta))
    (folder / "results.json").write_text(json.dumps(results))
    return folder
