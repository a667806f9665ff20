"""SPEC 14's must-show through `lps simulate --points` and `lps estimate`: targets at two depths resolve all
three angles of every stop, within 1.2x of what one view alone resolves; in one plane the tilts are not."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.two_depth import plan_two_depth
from lps_gui.core.truth.two_depth import one_plane_spec, two_depth_spec
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session

ANGLES = ("EAX", "EBX", "ECX")


def _estimate(folder, spec):
    simulate_point_session(spec, folder)
    return estimate_session(folder)


def _angles(results):
    """Per angle: median centred sigma / median single-view sigma, mean (error/sigma)^2 against truth, resolved."""
    em = results["error_motions"]
    out = {}
    for name in ANGLES:
        m = em["motions"][name]
        single = np.array(m["single_view_sigma"], float)
        out[name] = (np.nanmedian(np.array(m["centred_sigma"], float)) / np.nanmedian(single),
                     em["truth"][name]["z_mean_square"], em["resolved"][name], m["median_centred_sigma"])
    return out


def test_two_depths_through_the_session_pipeline(tmp_path):
    """600 mm in 61 stops (CI); the paper's 1524 mm axis in the slow test below."""
    spec = two_depth_spec(seed=1, plan=Plan(start_mm=0.0, stop_mm=600.0, step_mm=10.0))
    results = _estimate(tmp_path / "s", spec)
    angles = _angles(results)
    for name, (ratio, z2, resolved, sigma) in angles.items():
        assert ratio < 1.2, name
        assert resolved, name
        assert sigma < 15.0, name  # SPEC 14: about 11, 11 and 8 urad from one view of a full two-depth scene
    assert 0.5 < np.mean([a[1] for a in angles.values()]) < 2.0
    header, *rows = (tmp_path / "s" / "positions.csv").read_text().splitlines()
    assert header.split(",")[-6:] == ["eax_urad", "ebx_urad", "ecx_urad", "eax_sigma_urad", "ebx_sigma_urad",
                                      "ecx_sigma_urad"]
    assert all(all(cell != "" for cell in row.split(",")[-6:]) for row in rows[1:])
    assert results["error_motions"]["basis"].startswith("every stop's full pose")
    # plan-rig's prediction for this layout (noise-free corners, the estimator's model) within 20 %
    plan = plan_two_depth(spec.rig.intrinsics, 800.0, 600.0, 300.0, stops=61)
    for name, (_, _, _, sigma) in angles.items():
        assert abs(plan.angle_sigma_urad[name] / sigma - 1.0) < 0.2, name


def test_with_both_rows_in_one_plane_the_tilts_are_not_resolved(tmp_path):
    """Seed 8: the independent-noise rule calls EBX resolved (p-v 281 urad over a noise p-v of 274); the
    stops' angles correlate through the targets' chained tilts, and their full covariance's noise p-v is 318."""
    spec = one_plane_spec(seed=8, plan=Plan(start_mm=0.0, stop_mm=600.0, step_mm=10.0))
    results = _estimate(tmp_path / "s", spec)
    angles = _angles(results)
    assert not angles["EAX"][2] and not angles["EBX"][2]
    assert angles["EAX"][3] > 30.0 and angles["EBX"][3] > 30.0  # SPEC 14: 30-60 urad with both rows in one plane
    assert angles["ECX"][2]  # the rotation about the viewing direction stays resolved
    rows = (tmp_path / "s" / "positions.csv").read_text().splitlines()[1:]
    cells = [r.split(",")[-6:] for r in rows]
    assert all(c[0] == c[1] == c[3] == c[4] == "" for c in cells) and all(c[2] != "" for c in cells)


@pytest.mark.slow
def test_the_paper_axis_at_two_depths_over_ten_seeds(tmp_path):
    """The paper's 1524 mm X axis in 241 stops (preset paper-two-depth), 10 seeds."""
    ratios, z2, resolved = [], [], []
    for seed in range(10):
        angles = _angles(_estimate(tmp_path / f"s{seed}", two_depth_spec(seed=seed)))
        resolved.append([a[2] for a in angles.values()])
        ratios += [a[0] for a in angles.values()]
        z2 += [a[1] for a in angles.values()]
    # 29 of 30 with the stops' full covariance: seed 6's ECX (p-v 137 urad over a noise p-v of 89) lies along
    # the targets' chained mode, and its chi-square over 240 dof is p = 0.0014, not below 1e-3
    assert np.all(np.sum(resolved, axis=0) >= 9), resolved
    assert max(ratios) < 1.2
    assert 0.5 < np.mean(z2) < 2.0


@pytest.mark.slow
def test_the_paper_axis_in_one_plane_over_ten_seeds(tmp_path):
    """Preset paper-one-plane, 10 seeds: the tilts never reported resolved, the rotation about the view always."""
    for seed in range(10):
        angles = _angles(_estimate(tmp_path / f"s{seed}", one_plane_spec(seed=seed)))
        assert not angles["EAX"][2] and not angles["EBX"][2], seed
        assert angles["ECX"][2], seed
