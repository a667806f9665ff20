"""results.json positions built column by column equal the row-by-row build they replaced (issue 15), key order,
types, None for non-finite values and 'board not found' included."""
import math
from dataclasses import replace

import numpy as np

from lps_gui.core.estimator.estimate import estimate
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.session import Session
from lps_gui.pipeline.estimate import make_options, observations_from_session, position_rows
from lps_gui.sim.points import simulate_point_session


def _f(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _row_by_row(obs, est):
    """The previous position_rows with its per-view position_fields."""
    dev_um = est.deviation_um(obs.target_mm)
    six, bp = est.six_dof, est.board_plane
    rows = []
    for i in range(obs.K):
        row = {
            "index": int(obs.index[i]), "run": int(obs.run[i]), "direction": "+" if obs.direction[i] > 0 else "-",
            "target_mm": float(obs.target_mm[i]),
            "measured_mm": _f(est.state.s[i] + obs.target_mm[est.reference_view]) if est.usable[i] else None,
            "deviation_um": _f(dev_um[i]) if est.usable[i] else None,
            "sigma_um": _f(1e3 * est.sigma_s_mm[i]), "sigma_total_um": _f(1e3 * est.sigma_total_mm[i]),
            "step_sigma_um": _f(1e3 * est.step_sigma_mm[i]), "rms_px": _f(est.rms_px[i]),
            "n_corners": int(est.n_corners[i]), "outlier": bool(est.outlier[i]),
            "outlier_reason": est.outlier_reason[i] or ("board not found" if not est.usable[i] else ""),
            "used": bool(est.used[i]), "file": obs.names[i],
        }
        if six is not None:
            for j in (0, 1):
                row[f"pose_straightness_um_{j + 1}"] = _f(six.straightness_um[i, j])
                row[f"pose_straightness_sigma_um_{j + 1}"] = _f(six.straightness_sigma_um[i, j])
        if bp is not None:
            for j in (0, 1):
                row[f"straightness_um_{j + 1}"] = _f(bp.straightness_um[i, j])
                row[f"straightness_sigma_um_{j + 1}"] = _f(bp.straightness_sigma_um[i, j])
            row["image_rotation_urad"] = _f(bp.image_rotation_urad[i])
            row["image_rotation_sigma_urad"] = _f(bp.image_rotation_sigma_urad[i])
        elif six is not None:
            for j in (0, 1):
                row[f"straightness_um_{j + 1}"] = row[f"pose_straightness_um_{j + 1}"]
                row[f"straightness_sigma_um_{j + 1}"] = row[f"pose_straightness_sigma_um_{j + 1}"]
        if six is not None:
            for j, key in enumerate(("roll", "pitch", "yaw")):
                row[f"{key}_urad"] = _f(six.angles_urad[i, j])
                row[f"{key}_sigma_urad"] = _f(six.angles_sigma_urad[i, j])
        rows.append(row)
    return rows


def _same(new, old):
    assert len(new) == len(old)
    for a, b in zip(new, old):
        assert list(a) == list(b)
        assert all(type(a[k]) is type(b[k]) and a[k] == b[k] for k in a), (a, b)


def test_rows_equal_the_row_by_row_build(tmp_path):
    spec = replace(small_spec(seed=4, views=10, directions="both", runs=2), replaced_views=(3,), missing_fraction=0.02)
    simulate_point_session(spec, tmp_path / "s")
    obs = observations_from_session(Session.open(tmp_path / "s"))
    for method in ("joint", "pnp"):  # with and without the board-plane figures
        est = estimate(obs, make_options(method))
        _same(position_rows(obs, est), _row_by_row(obs, est))
    # a view whose board was not found, and non-finite figures: null in results.json
    est.usable = est.usable.copy()
    est.usable[5] = False
    est.rms_px = est.rms_px.copy()
    est.rms_px[2] = np.nan
    est.sigma_s_mm = est.sigma_s_mm.copy()
    est.sigma_s_mm[4] = np.inf
    new = position_rows(obs, est)
    _same(new, _row_by_row(obs, est))
    assert new[5]["measured_mm"] is None and new[5]["outlier_reason"] and new[2]["rms_px"] is None
