"""SPEC 7 files: round trips, crash safety and clear errors."""
import json

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import PAPER_INTRINSICS, paper_rig_spec, simulate_views, spec_from_dict, spec_to_dict
from lps_gui.errors import InputError
from lps_gui.io.board_file import read_board, write_board
from lps_gui.io.corners.vnl import CornerTable, read_corners_vnl, write_corners_vnl
from lps_gui.io.intrinsics_file import read_intrinsics, write_intrinsics
from lps_gui.io.session import CaptureRecord, Session


def test_board_round_trip(tmp_path):
    board = Board(cols=30, rows=18, square_mm=10.0)
    write_board(tmp_path / "board.json", board)
    assert json.loads((tmp_path / "board.json").read_text()) == {"type": "chessboard", "inner_corners": [30, 18], "square_mm": 10.0}
    assert read_board(tmp_path / "board.json") == board


@pytest.mark.parametrize("name", ["intrinsics.json", "intrinsics.yaml"])
def test_intrinsics_round_trip_with_std(tmp_path, name):
    std = np.array([0.5, 0.4, 0.3, 0.2, 1e-3, 2e-3, 1e-5, 2e-5, 3e-3])
    intr = CameraIntrinsics(PAPER_INTRINSICS.image_size, PAPER_INTRINSICS.camera_matrix, PAPER_INTRINSICS.dist,
                            covariance=np.diag(std**2), rms_px=0.12, n_views=20)
    write_intrinsics(tmp_path / name, intr)
    back = read_intrinsics(tmp_path / name)
    assert back.image_size == (1920, 1080)
    assert np.allclose(back.vector(), intr.vector(), rtol=1e-12)
    assert np.allclose(back.std(), std)


def test_opencv_yaml_has_opencv_node_names(tmp_path):
    write_intrinsics(tmp_path / "cam.yaml", PAPER_INTRINSICS)
    text = (tmp_path / "cam.yaml").read_text()
    for node in ("camera_matrix", "distortion_coefficients", "image_width", "image_height"):
        assert node in text


def test_corners_round_trip_with_missing_corners_and_failed_view(tmp_path):
    corners = np.random.default_rng(0).uniform(0, 100, (3, 6, 2))
    corners[0, 2] = np.nan
    corners[2] = np.nan
    table = CornerTable(["a.png", "b.png", "c.png"], corners, failed={"c.png": "board not found"}, meta={"captures_sha256": "abc"})
    write_corners_vnl(tmp_path / "corners.vnl", table)
    text = (tmp_path / "corners.vnl").read_text()
    assert text.startswith("# filename x y level\n") and "c.png - - -" in text
    back = read_corners_vnl(tmp_path / "corners.vnl", 6)
    assert back.names == table.names and back.failed == {"c.png": "board not found"} and back.meta["captures_sha256"] == "abc"
    assert np.allclose(back.corners_px, corners, atol=1e-4, equal_nan=True)


def test_corner_count_mismatch_names_file_and_fix(tmp_path):
    write_corners_vnl(tmp_path / "corners.vnl", CornerTable(["a.png"], np.zeros((1, 6, 2))))
    with pytest.raises(InputError, match="corners.vnl.*6 corners but the board has 8.*inner_corners"):
        read_corners_vnl(tmp_path / "corners.vnl", 8)


def test_session_append_survives_a_torn_line_and_resumes(tmp_path):
    plan = Plan(start_mm=0, stop_mm=4, step_mm=1, directions="both")
    session = Session.create(tmp_path / "s", Board(9, 6, 20.0), plan, intrinsics=PAPER_INTRINSICS)
    rel, sha = session.write_image("000000.png", b"pixels")
    session.append(CaptureRecord(0, 1, "+", 0.0, 0.0, rel, sha, 1.0))
    with open(session.captures_path, "a") as f:  # a crash in the middle of the next append
        f.write('{"index": 1, "run": 1, "direc')
    reopened = Session.open(tmp_path / "s")
    assert [r.index for r in reopened.records()] == [0]
    assert [s.index for s in reopened.remaining_stops()][:2] == [1, 2]
    reopened.append(CaptureRecord(1, 1, "+", 1.0, 1.0, "images/000001.png", None, 2.0))
    assert [r.index for r in Session.open(tmp_path / "s").records()] == [0, 1]
    assert len(reopened.remaining_stops()) == plan.n_frames() - 2
    assert not list((tmp_path / "s" / "images").glob("*.tmp"))


def test_session_refuses_to_overwrite(tmp_path):
    Session.create(tmp_path / "s", Board(9, 6, 20.0), Plan())
    with pytest.raises(InputError, match="already holds a session"):
        Session.create(tmp_path / "s", Board(9, 6, 20.0), Plan())


def test_rig_description_round_trip_reproduces_the_simulation():
    spec = paper_rig_spec(seed=4)
    again = spec_from_dict(json.loads(json.dumps(spec_to_dict(spec))))
    a, b = simulate_views(spec), simulate_views(again)
    assert np.allclose(a.corners_px, b.corners_px, atol=1e-9)
