"""`lps estimate` imports only what it uses (issue 15): the heavy modules stay out until a command needs them.

Checked in a fresh interpreter (sys.modules), not by timing: the CLI with every
command's parser built, plus the estimate command and its pipeline module.
"""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("scipy.signal", "scipy.stats", "scipy.spatial", "scipy.optimize", "PySide6", "pyqtgraph", "matplotlib", "cv2")

PROBE = """
import json, sys
import lps_gui.cli as cli
cli.build_parser()
import lps_gui.cli.estimate, lps_gui.pipeline.estimate
print(json.dumps(sorted(sys.modules)))
"""


@pytest.fixture(scope="module")
def loaded() -> list[str]:
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True, timeout=120)
    return json.loads(out.stdout)


@pytest.mark.parametrize("heavy", HEAVY)
def test_estimate_command_does_not_import(loaded, heavy):
    pulled = [m for m in loaded if m == heavy or m.startswith(heavy + ".")]
    assert not pulled, f"importing the estimate command pulls {pulled[:5]}; import it where it is used"
