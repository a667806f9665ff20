"""The paper's rig at full size (slow: run with -m slow): 1920x1080, 18x30 board."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.camera.detection import detect_chessboard
from lps_gui.camera.render import BoardRenderer
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec, true_views
from lps_gui.pipeline.detect import detect_session
from lps_gui.sim.images import simulate_image_session

pytestmark = pytest.mark.slow


def test_noise_free_paper_corners_within_0_03_px():
    spec = paper_rig_spec()
    _, R, t, _ = true_views(spec, np.random.default_rng(0))
    renderer = BoardRenderer(spec.rig.board, spec.rig.intrinsics)
    X = spec.rig.board.object_points()
    for k in (0, 199, 399):
        found = detect_chessboard(renderer.render(R[k], t[k]), spec.rig.board)
        truth = project_board(R[k], t[k], X, spec.rig.intrinsics)
        rms = np.sqrt(np.mean(np.sum((found - truth) ** 2, axis=1)))
        print(f"noise-free view {k}: corner RMS {rms:.4f} px")
        assert rms < 0.03


def test_paper_session_corner_rms_below_0_1_px(tmp_path):
    spec = paper_rig_spec(plan=Plan(start_mm=0.0, stop_mm=99.0, step_mm=1.0))
    simulate_image_session(spec, tmp_path / "s", noise_grey=2.0)
    table = detect_session(tmp_path / "s")
    _, R, t, _ = true_views(spec, np.random.default_rng(spec.seed))
    truth = project_board(R, t, spec.rig.board.object_points(), spec.rig.intrinsics)
    rms = float(np.sqrt(np.mean(np.sum((table.corners_px - truth) ** 2, axis=-1))))
    print(f"paper rig, 100 views, noise 2 grey levels: corner RMS {rms:.4f} px")
    assert not table.failed and rms < 0.1
