"""SPEC 14 on a planar stage: both axes' error motions from a constellation's full poses, through `lps estimate`."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.target_presets import constellation_errors, paper_constellation_spec
from lps_gui.core.truth.stage_errors import ErrorProfile, PlanarErrorModel
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


def test_a_constellation_gives_both_axes_yaw_and_not_their_tilts(tmp_path):
    """The paper's 1524 x 1016 mm gantry on a 7 x 5 grid against the 6 x 4 constellation (one depth)."""
    base = constellation_errors()
    x = replace(base.x, roll_urad=ErrorProfile(amplitude=80.0, period_mm=1524.0),
                yaw_urad=ErrorProfile(amplitude=100.0, period_mm=3048.0, phase_rad=1.57))
    y = replace(base.y, pitch_urad=ErrorProfile(poly=(0.0, -80.0)), yaw_urad=ErrorProfile(amplitude=90.0, period_mm=2032.0))
    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(1524.0, 1016.0), step_mm=(254.0, 254.0))
    spec = paper_constellation_spec(seed=0, errors=PlanarErrorModel(x, y, 150.0), plan=plan)
    simulate_point_session(spec, tmp_path / "s")
    results = estimate_session(tmp_path / "s")
    em = results["error_motions"]
    assert em["axes"] == ["X", "Y"]
    assert list(em["motions"]) == ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX", "EYY", "EXY", "EZY", "EAY", "EBY", "ECY"]
    assert em["motions"]["ECX"]["along"] == "X" and em["motions"]["ECY"]["along"] == "Y"
    assert len(em["motions"]["ECX"]["values"]) == 7 and len(em["motions"]["ECY"]["values"]) == 5
    assert em["resolved"]["ECX"] and em["resolved"]["ECY"]
    assert not any(em["resolved"][n] for n in ("EAX", "EBX", "EAY", "EBY"))  # one depth: the tilts are not resolved
    z2 = [em["truth"][n]["z_mean_square"] for n in ("ECX", "ECY")]
    assert 0.2 < np.mean(z2) < 3.0  # 7 + 5 values: a loose band
    for n in ("ECX", "ECY"):
        assert em["truth"][n]["rms_error_urad"] < 2.5 * em["motions"][n]["median_centred_sigma"]
    header, *rows = (tmp_path / "s" / "positions.csv").read_text().splitlines()
    assert header.split(",")[-6:] == ["eax_urad", "ebx_urad", "ecx_urad", "eax_sigma_urad", "ebx_sigma_urad",
                                      "ecx_sigma_urad"]
    cells = [r.split(",")[-6:] for r in rows]
    assert all(c[0] == c[1] == "" and c[2] != "" for c in cells)
    from lps_gui.report.pages.error_motions import error_motion_figures, error_motion_rows

    assert [f.key for f in error_motion_figures(results)] == ["error_motions_angular", "error_motions_linear",
                                                              "error_motions_angular_y", "error_motions_linear_y"]
    words = {r[0]: r[1] for r in error_motion_rows(results)}
    assert (words["EYY"], words["EBY"], words["EAY"], words["EXY"]) == ("positioning", "roll (about Y)", "pitch (about X)",
                                                                        "straightness along X")
