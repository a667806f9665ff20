"""The renderer against the camera model's projection (SPEC 2) and the exact-area claim."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.camera.sim_camera import SimulatedCamera
from lps_gui.core.clock import SimClock
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.truth.simulate import small_spec, true_views
from lps_gui.core.truth.stage_errors import TruePose
from lps_gui.errors import HardwareError


@pytest.fixture(scope="module")
def views():
    spec = small_spec(views=6)
    stops, R, t, _ = true_views(spec, np.random.default_rng(0))
    return spec, R, t


@pytest.fixture(scope="module")
def renderer(views):
    spec, _, _ = views
    return BoardRenderer(spec.rig.board, spec.rig.intrinsics)


def _subpix_rms(img, truth_uv, win=5):
    start = (truth_uv + 0.4).reshape(-1, 1, 2).astype(np.float32)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 100, 1e-5)
    found = cv2.cornerSubPix(img, start, (win, win), (-1, -1), crit).reshape(-1, 2)
    return float(np.sqrt(((found - truth_uv) ** 2).sum(1).mean()))


def test_noise_free_corners_sit_on_the_true_projection(views, renderer):
    spec, R, t = views
    X = spec.rig.board.object_points()
    for i in (0, 5):
        img = renderer.render(R[i], t[i])
        assert img.dtype == np.uint8 and img.shape == (480, 640)
        truth_uv = project_board(R[i], t[i], X, spec.rig.intrinsics)
        assert _subpix_rms(img, truth_uv) < 0.03


def test_point_sampling_is_biased_and_area_averaging_is_not(views):
    """A point-sampled render snaps edges to pixel centres (~0.3 px per axis); exact areas do not."""
    spec, R, t = views
    X = spec.rig.board.object_points()
    truth_uv = project_board(R[0], t[0], X, spec.rig.intrinsics)
    point = BoardRenderer(spec.rig.board, spec.rig.intrinsics, lighting=Lighting(antialias=False))
    area = BoardRenderer(spec.rig.board, spec.rig.intrinsics, lighting=Lighting(blur_px=0.0))
    assert _subpix_rms(point.render(R[0], t[0]), truth_uv) > 0.3
    img = area.render_float(R[0], t[0])
    values = np.unique(np.round(img[200:280, 250:350]))
    assert len(values) > 20  # edge pixels hold partial areas, not just black/white
    assert _subpix_rms(img, truth_uv) < 0.1  # unblurred: cornerSubPix itself limits this one


def test_black_and_white_levels_and_margin(views, renderer):
    spec, R, t = views
    img = renderer.render_float(R[0], t[0])
    lt = renderer.lighting
    assert img.min() >= lt.black - 1 and img.max() <= lt.white + 1
    uv0 = project_board(R[0], t[0], spec.rig.board.object_points()[:1], spec.rig.intrinsics)[0]
    # half a square up-left of corner 0 is the black corner square, 1.5 squares further is paper
    sq_px = uv0 - project_board(R[0], t[0], np.array([[spec.rig.board.square_mm, 0, 0]]), spec.rig.intrinsics)[0]
    side = abs(sq_px[0])
    inside = img[int(uv0[1] - side / 2), int(uv0[0] - side / 2)]
    paper = img[int(uv0[1] - 1.5 * side), int(uv0[0] - 1.5 * side)]
    assert inside < lt.black + 5 and paper > lt.white - 5


def test_noise_has_the_requested_sigma(views):
    spec, R, t = views
    r = BoardRenderer(spec.rig.board, spec.rig.intrinsics, noise_grey=2.0)
    clean = r.render_float(R[0], t[0])
    noisy = r.render(R[0], t[0], np.random.default_rng(3)).astype(float)
    sigma = np.std(noisy - clean)
    assert 1.9 < sigma < 2.15  # 2 grey levels plus 1/sqrt(12) quantization


def test_simulated_camera_renders_the_pose_source(views):
    spec, R, t = views
    pose = TruePose(np.array([10.0]), np.zeros((1, 2)), np.zeros((1, 3)))
    clock = SimClock()
    cam = SimulatedCamera(spec.rig, lambda: pose, noise_grey=0.0, clock=clock, exposure_s=0.01)
    with pytest.raises(HardwareError):
        cam.grab()
    with cam:
        frame = cam.grab()
    assert frame.size == spec.rig.intrinsics.image_size
    assert frame.time == pytest.approx(0.01)
    Rk, tk = spec.rig.camera_poses(pose)
    truth_uv = project_board(Rk[0], tk[0], spec.rig.board.object_points(), spec.rig.intrinsics)
    assert _subpix_rms(frame.image, truth_uv) < 0.03


def test_simulated_camera_follows_the_simulated_stage(views):
    """Moved by the simulated stage, the rendered board shifts as the rig's true pose says."""
    from lps_gui.camera.detection import detect_chessboard
    from lps_gui.hardware.sim_stage import SimulatedStage

    spec, _, _ = views
    clock = SimClock()
    stage = SimulatedStage(errors=spec.rig.errors, clock=clock)
    stage.connect()
    cam = SimulatedCamera(spec.rig, stage.true_pose, noise_grey=2.0, clock=clock)
    X = spec.rig.board.object_points()
    with cam:
        for target in (4.0, 10.0):
            stage.move_to(target, 600.0)
            stage.wait_idle()
            frame = cam.grab()
            R, t = spec.rig.camera_poses(stage.true_pose())
            truth = project_board(R[0], t[0], X, spec.rig.intrinsics)
            found = detect_chessboard(frame.image, spec.rig.board)
            assert np.sqrt(np.mean(np.sum((found - truth) ** 2, axis=1))) < 0.06
    assert clock.now() > 0.5  # the moves took simulated time, not real time
