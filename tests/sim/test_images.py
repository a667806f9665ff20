"""Rendered sessions carry the point simulator's truth; intrinsics sets vary their poses."""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from lps_gui.camera.detection import detect_chessboard
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.progress import CancelToken
from lps_gui.core.truth.simulate import simulate_views, small_spec, true_views
from lps_gui.errors import Cancelled, InputError
from lps_gui.io.atomic import sha256_file
from lps_gui.io.board_file import read_board
from lps_gui.io.intrinsics_file import read_intrinsics
from lps_gui.io.jsonfile import read_json
from lps_gui.io.session import Session
from lps_gui.sim.images import simulate_image_session, simulate_intrinsics_set


def test_session_truth_equals_point_simulator_and_images_show_it(tmp_path):
    spec = replace(small_spec(views=10), replaced_views=(3,), replaced_offset=5, bumped_views=(6,))
    session = simulate_image_session(spec, tmp_path / "s", workers=1)
    points = simulate_views(spec)
    assert session.truth["positions_mm"] == points.truth["positions_mm"]
    assert session.truth["bumped_views"] == [6] and session.truth["replaced_views"] == [3]
    records = Session.open(tmp_path / "s").records()
    assert [r.index for r in records] == list(range(10))
    assert session.intrinsics().image_size == (640, 480)
    _, R, t, _ = true_views(spec, np.random.default_rng(spec.seed))
    X = spec.rig.board.object_points()
    for k, shown in [(0, 0), (3, 8), (6, 6)]:  # view 3 shows view 8's image; view 6 is bumped
        rec = records[k]
        assert sha256_file(tmp_path / "s" / rec.file) == rec.sha256
        img = cv2.imread(str(tmp_path / "s" / rec.file), cv2.IMREAD_GRAYSCALE)
        found = detect_chessboard(img, spec.rig.board)
        truth = project_board(R[shown], t[shown], X, spec.rig.intrinsics)
        assert np.sqrt(np.mean(np.sum((found - truth) ** 2, axis=1))) < 0.06


def test_session_refuses_an_existing_session_and_cancel_keeps_listed_images(tmp_path):
    spec = small_spec(views=5)
    token = CancelToken()

    def progress(done, total, msg=""):
        if done >= 2:
            token.cancel()

    with pytest.raises(Cancelled):
        simulate_image_session(spec, tmp_path / "s", progress, token, workers=1)
    records = Session.open(tmp_path / "s").records()
    assert len(records) == 2 and all((tmp_path / "s" / r.file).exists() for r in records)
    with pytest.raises(InputError):
        simulate_image_session(spec, tmp_path / "s", workers=1)


def test_intrinsics_set_is_varied_and_fully_in_view(tmp_path):
    spec = small_spec()
    paths = simulate_intrinsics_set(tmp_path / "set", spec.rig.board, spec.rig.intrinsics, n_views=8, seed=3)
    assert len(paths) == 8 and all(p.exists() for p in paths)
    assert read_board(tmp_path / "set" / "board.json") == spec.rig.board
    assert np.allclose(read_intrinsics(tmp_path / "set" / "intrinsics_truth.json").vector(), spec.rig.intrinsics.vector())
    poses = read_json(tmp_path / "set" / "poses_truth.json")
    R = np.array(poses["R_cam_board"])
    tilt_deg = np.degrees(np.arccos(np.clip(R[:, 2, 2], -1, 1)))
    assert tilt_deg.max() > 25 and tilt_deg.max() <= 45.5
    normals = R[:, :, 2]
    assert np.degrees(np.arccos(np.clip(normals @ normals.T, -1, 1))).max() > 40  # tilted in different directions
    uv = project_board(R, np.array(poses["t_cam_board_mm"]), spec.rig.board.object_points(), spec.rig.intrinsics)
    assert uv.min() >= 0 and uv[..., 0].max() < 640 and uv[..., 1].max() < 480
    w, h = spec.rig.intrinsics.image_size
    reach = max(uv[..., 0].max() / w, 1 - uv[..., 0].min() / w, uv[..., 1].max() / h, 1 - uv[..., 1].min() / h)
    assert reach > 0.9  # corners reach near the image edges
