"""Closed loop: capture on the simulated rig, detect, estimate, and recover the stage's error model.

The estimator (issue 3) sees only the images; the simulated stage's
StageErrorModel (scale, lead-screw periodic error, backlash, repeatability)
is the truth. Tolerances come from the estimate's own sigmas.
"""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.io.session import Session
from tests.capture.helpers import start_capture


@pytest.mark.slow
def test_estimator_recovers_the_simulated_stage_error_model(tmp_path):
    from lps_gui.pipeline.detect import detect_session
    from lps_gui.pipeline.estimate import estimate_session

    session, stage, camera, engine = start_capture(tmp_path / "s", full_size=True)
    assert engine.run().state == "done"
    detect_session(session.folder, workers=1)
    results = estimate_session(session.folder, method="joint")

    tc = results["truth_comparison"]
    assert tc["position_rms_error_um"] < 3 * tc["mean_sigma_um"]
    assert tc["flagged_outliers"] == []

    # fit the stage's error model to the measured deviations: offset, scale, periodic (known pitch), backlash
    errors = stage.errors
    pos = results["positions"]
    x = np.array([p["target_mm"] for p in pos])
    d = np.array([1.0 if p["direction"] == "+" else -1.0 for p in pos])
    dev_um = np.array([p["deviation_um"] for p in pos])
    sigma_um = np.hypot(np.array([p["sigma_um"] for p in pos]), errors.repeatability_um)
    w = 2 * np.pi * x / errors.pitch_mm
    A = np.stack([np.ones_like(x), 1e-3 * x, np.sin(w), np.cos(w), -0.5 * d], axis=1)  # um per: 1, ppm, sin, cos, backlash
    coef, *_ = np.linalg.lstsq(A / sigma_um[:, None], dev_um / sigma_um, rcond=None)
    cov = np.linalg.inv((A / sigma_um[:, None]).T @ (A / sigma_um[:, None]))
    sd = np.sqrt(np.diag(cov))
    print(f"scale {coef[1]:.1f}+-{sd[1]:.1f} ppm (true {errors.scale_ppm}), periodic {np.hypot(coef[2], coef[3]):.2f}+-{max(sd[2], sd[3]):.2f} um (true {errors.periodic_um}), backlash {coef[4]:.2f}+-{sd[4]:.2f} um (true {errors.backlash_um}); position rms error {tc['position_rms_error_um']:.2f} um, mean sigma {tc['mean_sigma_um']:.2f} um")
    assert coef[1] == pytest.approx(errors.scale_ppm, abs=4 * sd[1])
    amplitude, amplitude_sd = np.hypot(coef[2], coef[3]), max(sd[2], sd[3])
    assert amplitude == pytest.approx(errors.periodic_um, abs=4 * amplitude_sd)
    assert coef[4] == pytest.approx(errors.backlash_um, abs=4 * sd[4])
    # and the estimate is precise enough for that to mean something
    assert max(sd[2], sd[3], sd[4]) < 0.5 * min(errors.periodic_um, errors.backlash_um)
    assert Session.open(session.folder).truth["simulated"]
