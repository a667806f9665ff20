"""The results' key columns are named once (issue 34): a literal such as "deviation_um" lives in io/results/keys.py
(and core/metrology/iso230_run.py, which core needs without importing io), every other module imports the name."""
from __future__ import annotations

from pathlib import Path

import pytest

from lps_gui.io.results import keys

PACKAGE = Path(__file__).resolve().parents[2] / "lps_gui"
ALLOWED = {"io/results/keys.py", "core/metrology/iso230_run.py"}


@pytest.mark.parametrize("key", [keys.DEVIATION_UM, keys.MEASURED_MM, keys.SIGMA_TOTAL_UM])
def test_a_key_column_is_spelled_in_at_most_two_modules(key):
    spelled = {str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py") if f'"{key}"' in p.read_text(encoding="utf-8")}
    assert spelled <= ALLOWED, f'"{key}" spelled out in {sorted(spelled - ALLOWED)}: import it from io/results/keys.py'
