"""Shared fixture: one uninterrupted capture of the must-show plan (20 targets, both directions, 2 runs)."""
from __future__ import annotations

import pytest

from tests.capture.helpers import start_capture


@pytest.fixture(scope="session")
def reference_capture(tmp_path_factory):
    """The uninterrupted 80-frame capture of PLAN20: (session, summary, stage)."""
    session, stage, camera, engine = start_capture(tmp_path_factory.mktemp("ref") / "session")
    summary = engine.run()
    return session, summary, stage
