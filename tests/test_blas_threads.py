"""The entry points default OpenBLAS to one thread before numpy loads, and keep a value the user set."""
from __future__ import annotations

import os
import subprocess
import sys

CHILD = """
import contextlib, io, os
from lps_gui.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main(['--version'])
    except SystemExit:
        pass
import numpy
print(os.environ['OPENBLAS_NUM_THREADS'])
"""


def _child_value(env_value: str | None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if env_value is not None:
        env["OPENBLAS_NUM_THREADS"] = env_value
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_lps_defaults_openblas_to_one_thread():
    assert _child_value(None) == "1"


def test_a_value_the_user_set_is_kept():
    assert _child_value("3") == "3"
