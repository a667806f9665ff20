"""Sessions for the reliability tests (issue 17): a point-level one (fast) and a small imaged one."""
from __future__ import annotations

import shutil
from dataclasses import replace

import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import small_spec
from lps_gui.sim.points import simulate_point_session

PLAN6 = Plan(start_mm=0.0, stop_mm=10.0, step_mm=2.0, directions="+", runs=1, overshoot_mm=1.0, settle_s=0.0, feed_mm_min=1200.0)


@pytest.fixture()
def point_session(tmp_path):
    """A simulated point-level session (corners.vnl, no images): estimate runs in well under a second."""
    spec = small_spec(seed=3, views=10, directions="+", runs=1)
    simulate_point_session(spec, tmp_path / "s")
    return tmp_path / "s"


@pytest.fixture(scope="session")
def _imaged_session(tmp_path_factory):
    from tests.capture.helpers import start_capture

    folder = tmp_path_factory.mktemp("imaged") / "s"
    session, stage, camera, engine = start_capture(folder, plan=PLAN6)
    assert engine.run().state == "done"
    return folder


@pytest.fixture()
def imaged_session(_imaged_session, tmp_path):
    """A copy of a small captured session with 320x240 images (6 frames), not yet detected."""
    folder = tmp_path / "imaged"
    shutil.copytree(_imaged_session, folder)
    return folder


def no_space(*_a, **_k):
    import errno
    import os

    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


__all__ = ["PLAN6", "no_space", "replace"]
