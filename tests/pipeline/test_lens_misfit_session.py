"""A session whose true lens has rational and thin-prism terms, estimated with a 5-coefficient calibration (issue 35).

Before the lens-model uncertainty, the misfit faked a smooth pitch profile that was called resolved and the Abbe term
multiplied it by the board distance: U of A 550-700 um against 10 um without the misfit (seeds 0-2).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
from lps_gui.core.truth.lens_misfit import with_lens_misfit
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.intrinsics_file import write_intrinsics
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.images import sample_intrinsics_poses
from lps_gui.sim.points import simulate_point_session


def _session(out: Path, misfit_px: float, seed: int = 0) -> dict:
    """A point session of the small rig, estimated with intrinsics calibrated from a separate set of the same lens."""
    spec = with_lens_misfit(small_spec(seed=seed, views=12, noise_px=0.03, directions="both", runs=2), misfit_px)
    rng = np.random.default_rng(seed + 1)
    board, true = spec.rig.board, spec.rig.intrinsics
    X = board.object_points()
    views = [project_board(R, t, X, true) + rng.normal(0.0, spec.noise_px, (len(X), 2))
             for R, t in sample_intrinsics_poses(board, true, 20, rng)]
    cal = calibrate_intrinsics(X, views, true.image_size)
    simulate_point_session(spec, out)
    write_intrinsics(out / "calibrated.json", cal.intrinsics)
    return estimate_session(out, intrinsics_path=out / "calibrated.json")


def _lens_flags(results: dict) -> list[str]:
    return [f["message"] for f in results["flags"] if f.get("kind") == "lens_model"]


def test_lens_misfit_resolves_no_angle_keeps_u_and_is_flagged(tmp_path):
    clean = _session(tmp_path / "clean", 0.0)
    misfit = _session(tmp_path / "misfit", 0.3)
    assert not _lens_flags(clean)
    assert not any(clean["error_motions"]["resolved"][n] for n in ("EAX", "EBX", "ECX"))
    flags = _lens_flags(misfit)
    assert flags and "lps intrinsics --model rational" in flags[0]
    assert not any(misfit["error_motions"]["resolved"][n] for n in ("EAX", "EBX", "ECX"))
    u_clean, u_misfit = clean["uncertainty"]["expanded_k2_um"], misfit["uncertainty"]["expanded_k2_um"]
    assert u_misfit < 3.0 * u_clean, (u_misfit, u_clean)
    lens = misfit["error_motions"]["lens_model"]
    assert lens["carried_by_poses"] and lens["misfit_px"] > lens["calibration"]["noise_px"]
    abbe = next(r for r in misfit["uncertainty"]["budget"] if r["source"] == "Abbe offset")
    assert "not resolved: no term" in abbe["note"]
    # the truth comparison is made after the error motions: its z test scores the sigma the bands draw, lens in
    ref = misfit["parameters"]["reference_index"]
    rows = [r for r in misfit["positions"] if r["used"] and r["index"] != ref]
    assert any(r.get("sigma_lens_um") for r in rows)  # the lens misfit is in sigma_total_um
    z2 = np.mean([((r["deviation_um"] - r["truth_deviation_um"]) / r["sigma_total_um"]) ** 2 for r in rows])
    assert misfit["truth_comparison"]["z_mean_square"] == pytest.approx(z2, rel=1e-9)
