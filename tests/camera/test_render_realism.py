"""The simulator's realism (issue 35): the rendered lens is the true lens, beyond what the Brown model can say;
off by default."""
from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.truth.realism import REALISM, brown_residual_px, printed_rng
from lps_gui.core.truth.simulate import PAPER_INTRINSICS, small_spec, true_views


def test_realism_is_off_by_default_and_one_field_turns_everything_on():
    spec = small_spec()
    assert spec.realism is None and spec.camera_realism() == {} and spec.realism_truth() == {}
    on = replace(spec, realism=REALISM["on"])
    opts = on.camera_realism()
    assert set(opts) == {"lens", "printed", "blur_edge_px", "vignetting", "shot_gain"}
    printed = opts["printed"]
    assert printed.square_mm != spec.rig.board.square_mm and printed.warp_mm != (0.0, 0.0)
    assert on.printed() == printed  # the same draw every time (the prints' own stream of the seed)
    truth = true_views(on, np.random.default_rng(0))[3]["realism"]
    assert truth["printed"][0]["square_mm"] == printed.square_mm and truth["lens"]["s1"] != 0.0


def test_the_lens_misfit_has_the_sizes_the_issue_asks_for():
    """On: 0.03-0.06 px beyond the best 5-coefficient fit; strong: 0.15-0.3 px; on two cameras."""
    for intr in (small_spec().rig.intrinsics, PAPER_INTRINSICS):
        assert 0.03 < brown_residual_px(intr, REALISM["on"].lens(intr))[0] < 0.06
        assert 0.15 < brown_residual_px(intr, REALISM["strong"].lens(intr))[0] < 0.3


def test_corners_render_where_the_true_lens_puts_them_not_where_the_brown_model_does():
    spec = small_spec()
    intr = spec.rig.intrinsics
    lens = REALISM["strong"].lens(intr)
    board = spec.rig.board
    R = cv2.Rodrigues(np.array([0.15, -0.2, 0.05]))[0]
    t = np.array([-90.0, -60.0, 420.0])
    img = BoardRenderer(board, intr, lighting=Lighting(blur_px=0.8), lens=lens).render(R, t)
    found, corners = cv2.findChessboardCorners(img, board.inner_corners)
    assert found
    corners = cv2.cornerSubPix(img, corners, (5, 5), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)).reshape(-1, 2)
    X = board.object_points()
    x_cam = X @ R.T + t
    truth = lens.project(x_cam, intr)
    brown = project_board(R, t, X, intr)
    if np.linalg.norm(corners[0] - truth[0]) > np.linalg.norm(corners[0] - truth[-1]):
        corners = corners[::-1]  # OpenCV may number the grid from the other end
    to_truth = np.sqrt(np.mean(np.sum((corners - truth) ** 2, axis=1)))
    to_brown = np.sqrt(np.mean(np.sum((corners - brown) ** 2, axis=1)))
    assert to_truth < 0.05 and to_brown > 0.15, (to_truth, to_brown)  # 0.027 and 0.19 px


def test_blur_grows_to_the_corners_and_keeps_the_centre():
    spec = small_spec()
    img = np.zeros((480, 640), np.float32)
    img[:, 320:] = 200.0
    img[240:, :] = 200.0 - img[240:, :]
    sharp = BoardRenderer(spec.rig.board, spec.rig.intrinsics, lighting=Lighting(blur_px=1.0))
    varying = BoardRenderer(spec.rig.board, spec.rig.intrinsics, rays=sharp.rays,
                            lighting=Lighting(blur_px=1.0, blur_edge_px=3.0))
    a, b = sharp.optics(img.copy()), varying.optics(img.copy())
    assert np.abs(a[235:245, 315:325] - b[235:245, 315:325]).max() < 2.0  # the centre as sharp as before
    assert np.abs(a[:200, :8] - b[:200, :8]).max() < 1e-3  # far from edges nothing to blur either way
    edge = np.abs(a[:20, 300:340] - b[:20, 300:340]).max()  # an edge near the top: softer there
    assert edge > 5.0


def test_the_prints_draws_are_their_own_stream():
    a, b = printed_rng(4).standard_normal(3), printed_rng(4).standard_normal(3)
    assert np.array_equal(a, b) and not np.array_equal(a, np.random.default_rng(4).standard_normal(3))


def test_lps_simulate_realism_records_the_true_lens_and_prints_and_refuses_points(tmp_path, capsys):
    import json

    from lps_gui.cli import main
    assert main(["simulate", str(tmp_path / "s"), "--realism", "strong", "--stops", "3", "--directions", "+",
                 "--runs", "1"]) == 0
    real = json.loads((tmp_path / "s" / "session.json").read_text())["truth"]["realism"]
    assert real["lens_px"] == REALISM["strong"].lens_px and len(real["printed"]) == 1 and real["lens"]["k4"] != 0
    assert main(["simulate", str(tmp_path / "p"), "--points", "--realism", "on"]) != 0
    assert "drop --points" in capsys.readouterr().err
