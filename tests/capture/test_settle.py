"""Settle detection on a stage that rings after each move, and frame averaging, against simulator truth."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.camera.base import Camera, Frame
from lps_gui.capture.settle import SettleOptions, Settler, average_frames, board_shift_px
from lps_gui.core.clock import SimClock
from lps_gui.errors import InputError
from lps_gui.io.session import CaptureRecord
from tests.capture.vibration_helpers import FRAME_S, RINGING, position_errors_mm, vibrating_capture

SETTLE = SettleOptions(settle_px=0.01, timeout_s=3.0)


@pytest.fixture(scope="module")
def ringing_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("ringing")
    return {name: vibrating_capture(root / name, settle) for name, settle in (("fixed", None), ("settled", SETTLE))}


def test_settle_detection_cuts_the_position_error_of_a_ringing_stage_3x(ringing_runs):
    rms = {name: float(np.sqrt(np.mean(position_errors_mm(*run) ** 2))) for name, run in ringing_runs.items()}
    # without it the frame is taken while the carriage still swings by about the ringing amplitude
    assert rms["fixed"] > 0.5e-3 * RINGING.amplitude_um
    assert rms["settled"] * 3.0 <= rms["fixed"], rms


def test_the_settle_time_is_recorded_per_stop_and_the_options_in_session_json(ringing_runs):
    fixed, settled = ringing_runs["fixed"][0], ringing_runs["settled"][0]
    assert all(r.settle_s is None for r in fixed.records())
    assert "settle_s" not in (fixed.folder / "captures.jsonl").read_text()  # without settle detection: the old lines
    times = [r.settle_s for r in settled.records()]
    # frames come every 40 ms; the ringing (decay 0.25 s) takes several of them to fall under 0.01 px
    assert all(t is not None and 4 * FRAME_S <= t < SETTLE.timeout_s for t in times), times
    meta = json.loads((settled.folder / "session.json").read_text())
    assert meta["acquisition"] == {"average_frames": 1, "settle_px": 0.01, "settle_timeout_s": 3.0, "settle_frames": 3}
    assert "acquisition" not in json.loads((fixed.folder / "session.json").read_text())
    assert meta["stage"]["vibration"] == RINGING.to_dict()


def test_old_capture_lines_without_settle_time_stay_valid():
    line = '{"index":0,"run":1,"direction":"+","target_mm":0.0,"reported_mm":0.0,"file":"images/000000.png","sha256":null,"time":1.0,"frame":0}'
    record = CaptureRecord.from_dict(json.loads(line))
    assert record.settle_s is None and record.to_json() == line
    with_settle = CaptureRecord.from_dict({**json.loads(line), "settle_s": 0.25})
    assert with_settle.settle_s == 0.25 and json.loads(with_settle.to_json())["settle_s"] == 0.25
    with pytest.raises(ValueError, match="settle_s"):
        CaptureRecord.from_dict({**json.loads(line), "settle_s": "soon"})


class StillCamera(Camera):
    """A board that never moves and a clock that never advances: settling must still end."""

    def __init__(self, image):
        self.image, self.grabs = image, 0

    def open(self):
        self._open = True

    def grab(self):
        self.grabs += 1
        return Frame(self.image, 0.0)


def test_settling_ends_on_a_frozen_clock_and_a_board_that_is_never_found(tmp_path):
    from lps_gui.core.geometry.board import Board

    camera = StillCamera(np.full((60, 80), 128, np.uint8))  # no board in view
    settler = Settler(Board(cols=9, rows=6, square_mm=20.0), SettleOptions(settle_px=0.01, timeout_s=1.0), SimClock())
    got = settler.grab(camera, settle=True)
    assert not got.settled and camera.grabs > 100  # bounded by MAX_GRABS, not by the (frozen) clock


def test_averaging_n_frames_shrinks_the_corner_noise_as_one_over_root_n(tmp_path):
    from lps_gui.camera.detection import detect_chessboard
    from lps_gui.camera.render import BoardRenderer
    from lps_gui.core.truth.stage_errors import TruePose
    from tests.capture.helpers import tiny_spec

    rig = tiny_spec().rig
    R, t = rig.camera_poses(TruePose(axis_mm=np.array([19.0]), straightness_um=np.zeros((1, 2)), angles_urad=np.zeros((1, 3))))
    clean = detect_chessboard(BoardRenderer(rig.board, rig.intrinsics, 1.0, noise_grey=0.0).render(R[0], t[0], np.random.default_rng(0)), rig.board)
    noisy = BoardRenderer(rig.board, rig.intrinsics, 1.0, noise_grey=4.0)
    rng = np.random.default_rng(1)

    def corner_rms(n: int, trials: int = 12) -> float:
        errs = []
        for _ in range(trials):
            frames = [Frame(noisy.render(R[0], t[0], rng), 0.0) for _ in range(n)]
            errs.append(detect_chessboard(average_frames(frames).image, rig.board) - clean)
        return float(np.sqrt(np.mean(np.square(errs))))

    one, four = corner_rms(1), corner_rms(4)
    assert 0.35 < four / one < 0.7, (one, four)  # 1/sqrt(4) = 0.5


def test_board_shift_is_the_mean_displacement():
    a = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert board_shift_px(a, a + [0.3, 0.4]) == pytest.approx(0.5)


@pytest.mark.parametrize("kw,flag", [({"settle_px": 0.0}, "--settle-px"), ({"timeout_s": -1}, "--settle-timeout-s"),
                                     ({"average": 0}, "--average-frames"), ({"agree_frames": 1}, "--settle-frames")])
def test_bad_options_are_one_line(kw, flag):
    with pytest.raises(InputError, match=f"^{flag}"):
        SettleOptions(**kw)
