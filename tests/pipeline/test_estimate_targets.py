"""A session with targets (SPEC 13) through the one estimation path, against simulator truth."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest

from lps_gui.core.board import Board
from lps_gui.core.camera_model import CameraIntrinsics
from lps_gui.core.plan import Plan
from lps_gui.core.rotation import exp_so3
from lps_gui.core.target_rig import observe, row_layout
from lps_gui.core.targets import pack_targets, target_offsets
from lps_gui.errors import LpsError
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.io.target_corners_vnl import TargetCornerTable, write_target_corners
from lps_gui.pipeline.estimate import estimate_session

CAMERA = CameraIntrinsics.from_values((1920, 1080), 2319.0, 2319.0, 960.0, 540.0)
BOARD = Board(10, 7, 30.0, type="charuco", marker_mm=22.0)


def row_session(folder, n_targets=3, stops=31, step_mm=12.7, seed=0, cut_target=None):
    """A row of targets seen from a line, written as capture + detection would (corners.vnl of SPEC 13)."""
    targets = pack_targets([BOARD] * n_targets)
    layout = row_layout(targets, 340.0, tilt_sigma_rad=0.01, offset_sigma_mm=2.0, seed=seed)
    plan = Plan(start_mm=0.0, stop_mm=(stops - 1) * step_mm, step_mm=step_mm)
    x = plan.targets()
    R = exp_so3(np.array([0.01, -0.02, 0.005]))
    span = (n_targets - 1) * 340.0 + BOARD.size_mm[0]
    t = R @ np.array([-(span - x[-1]) / 2, -90.0, 0]) + np.array([0, 0, 800.0]) + x[:, None] * (R @ [-1.0, 0, 0])
    uv = observe(layout, CAMERA, R, t, noise_px=0.1, seed=seed)
    if cut_target is not None:  # the views that see this target see nothing else: it is not tied
        offsets = target_offsets(targets)
        own = np.zeros(uv.shape[1], bool)
        own[offsets[cut_target]: offsets[cut_target + 1]] = True
        sees = np.isfinite(uv[:, own, 0]).any(axis=1)
        uv[np.ix_(sees, ~own)] = np.nan
    session = Session.create(folder, targets, plan, intrinsics=CAMERA)
    names = [f"images/{i:06d}.png" for i in range(len(x))]
    for name, stop in zip(names, plan.stops()):
        session.append(CaptureRecord(stop.index, stop.run, stop.direction, stop.target_mm, stop.target_mm, name, None,
                                     time.time(), stop.frame))
    write_target_corners(session.corners_path, TargetCornerTable(names, [t.id for t in targets],
                                                                 target_offsets(targets), uv))
    return session, layout, x


def test_a_row_session_is_estimated_with_its_targets_section(tmp_path):
    session, layout, x = row_session(tmp_path / "row")
    results = estimate_session(session.folder)
    assert list(results).index("targets") == list(results).index("board") + 1
    rows = results["targets"]
    assert [r["id"] for r in rows] == ["T0", "T1", "T2"]
    for j, r in enumerate(rows):
        assert set(r) >= {"rvec_rad", "rvec_sigma_rad", "p_mm", "p_sigma_mm", "views", "ties", "seen_by", "tied_by"}
        assert len(r["seen_by"]) == r["views"] and len(r["tied_by"]) == r["ties"] > 0
        if j:
            assert np.all(np.abs(np.array(r["p_mm"]) - layout.p[j]) < 4 * np.array(r["p_sigma_mm"]))
    assert sum(r["covered_fraction"] for r in rows) == pytest.approx(1.0)
    sources = [b["source"] for b in results["uncertainty"]["budget"]]
    assert [s for s in sources if s.startswith("target scale")] == ["target scale T0", "target scale T1",
                                                                   "target scale T2"]
    assert "board square size" not in sources
    on_disk = json.loads((session.folder / "results.json").read_text())
    assert on_disk["targets"][1]["p_mm"] == rows[1]["p_mm"]
    assert (session.folder / "positions.csv").read_text().count("\n") == len(x) + 1
    dev = np.array([p["deviation_um"] for p in results["positions"]])
    sigma = np.array([p["sigma_um"] for p in results["positions"]])
    assert np.all(np.abs(dev[1:]) < 5 * sigma[1:])  # a perfect stage: deviations are noise


def test_each_printed_scale_enters_the_stretch_of_its_target(tmp_path):
    session, _, x = row_session(tmp_path / "row")
    session.meta["targets"][1]["square_mm_uncertainty_um"] = 2.0
    session.save_meta()
    results = estimate_session(session.folder)
    row = next(b for b in results["uncertainty"]["budget"] if b["source"] == "target scale T1")
    share = results["targets"][1]["covered_fraction"]
    assert row["contribution_um"] == pytest.approx(2.0 * share * (x[-1] - x[0]) / 30.0)
    assert results["uncertainty"]["combined_standard_um"] > row["contribution_um"]


def test_an_untied_target_is_a_one_line_error_and_nothing_is_written(tmp_path):
    session, _, _ = row_session(tmp_path / "row", n_targets=4, stops=121, cut_target=3)
    with pytest.raises(LpsError) as err:
        estimate_session(session.folder)
    message = str(err.value)
    assert "\n" not in message and "target T3 is not tied to target T0" in message and "images/" in message
    assert not (session.folder / "results.json").exists()
