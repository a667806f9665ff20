"""Guided intrinsics capture: a simulated hand-held board held as each goal asks, checked, stored, calibrated."""
from __future__ import annotations

import json

import numpy as np
import pytest

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.render import BoardRenderer
from lps_gui.capture.intrinsics_plan import (
    LIST_FILE,
    IntrinsicsCapture,
    check_view,
    coverage,
    goal_pose,
    intrinsics_plan,
)
from lps_gui.core.geometry.camera_model import project
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.atomic import sha256_file


class HandHeldBoard(Camera):
    """Renders the board wherever the 'operator' holds it (``pose``), with seeded noise."""

    def __init__(self, board, intrinsics):
        self.renderer = BoardRenderer(board, intrinsics, noise_grey=1.0)
        self.pose = None
        self.rng = np.random.default_rng(0)

    def open(self):
        pass

    def close(self):
        pass

    @property
    def is_open(self):
        return True

    def grab(self):
        return Frame(self.renderer.render(*self.pose, self.rng), time=0.0)


def test_plan_is_varied():
    goals = intrinsics_plan(15)
    assert len(goals) == 15 and len({g.name for g in goals}) == 15
    tilts = np.array([g.tilt_deg for g in goals])
    assert (tilts[:, 0] > 0).any() and (tilts[:, 0] < 0).any() and (tilts[:, 1] > 0).any() and (tilts[:, 1] < 0).any()
    centres = np.array([g.centre for g in goals])
    assert centres[:, 0].min() < 0.35 and centres[:, 0].max() > 0.65 and centres[:, 1].min() < 0.35 and centres[:, 1].max() > 0.65


def test_goal_pose_puts_the_board_where_asked():
    spec = small_spec()
    board, intr = spec.rig.board, spec.rig.intrinsics
    for goal in intrinsics_plan(21):
        R, t = goal_pose(goal, board, intr)
        uv = project((board.object_points() @ R.T) + t, intr).uv
        assert check_view(uv, goal, intr.image_size).ok, goal.name
        w, h = intr.image_size
        assert (uv >= 0).all() and (uv[:, 0] <= w - 1).all() and (uv[:, 1] <= h - 1).all(), goal.name


def test_guided_capture_checks_stores_resumes_and_calibrates(tmp_path):
    from lps_gui.pipeline.intrinsics import calibrate_images

    spec = small_spec()
    board, intr = spec.rig.board, spec.rig.intrinsics
    cam = HandHeldBoard(board, intr)
    goals = intrinsics_plan(12)
    cap = IntrinsicsCapture(cam, tmp_path / "intr", board, goals)
    # the operator holds the first view in the wrong place: refused, nothing stored
    cam.pose = goal_pose(goals[5], board, intr)  # top-left instead of centre
    refused = cap.take()
    assert refused.found and not refused.ok and "not where asked" in refused.message
    assert not (tmp_path / "intr" / LIST_FILE).exists()
    corners = []
    for goal in goals[:6]:
        assert cap.current() == goal
        cam.pose = goal_pose(goal, board, intr)
        result = cap.take()
        assert result.ok, (goal.name, result.message)
        corners.append(result.corners_px)
    # interrupted: a new capture object on the same folder resumes at view 7
    cap = IntrinsicsCapture(cam, tmp_path / "intr", board, goals)
    assert cap.current() == goals[6]
    for goal in goals[6:]:
        cam.pose = goal_pose(goal, board, intr)
        result = cap.take()
        assert result.ok, (goal.name, result.message)
        corners.append(result.corners_px)
    assert cap.done and "every view" in cap.take().message
    lines = [json.loads(line) for line in (tmp_path / "intr" / LIST_FILE).read_text().splitlines()]
    assert [d["goal"] for d in lines] == [g.name for g in goals]
    for d in lines:
        assert sha256_file(tmp_path / "intr" / d["file"]) == d["sha256"]
    assert coverage(corners, intr.image_size) > 0.6

    cal = calibrate_images([tmp_path / "intr"], board, workers=1)
    est = cal.intrinsics
    assert est.camera_matrix[0, 0] == pytest.approx(intr.camera_matrix[0, 0], rel=0.01)
    assert est.camera_matrix[0, 2] == pytest.approx(intr.camera_matrix[0, 2], abs=3.0)
    assert est.dist[0] == pytest.approx(intr.dist[0], abs=0.03)
