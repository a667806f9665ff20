"""ISO 14253-1: the uncertainty zone around the limit is neither PASS nor FAIL."""
from __future__ import annotations

import math

import pytest

from lps_gui.core.metrology.decision_rule import decide


@pytest.mark.parametrize("measured,u,expected", [
    (5.0, 2.0, "PASS"),          # 5 + 2 <= 10
    (9.0, 2.0, "not resolved"),  # 9 + 2 > 10: the limit is inside 9 +- 2
    (11.0, 2.0, "not resolved"), # 11 - 2 <= 10
    (13.0, 2.0, "FAIL"),         # 13 - 2 > 10
    (9.0, None, "PASS"),         # no U: the bare comparison
    (11.0, math.nan, "FAIL"),
])
def test_the_uncertainty_zone(measured, u, expected):
    assert decide(measured, 10.0, measured <= 10.0, u) == expected


def test_not_compared():
    assert decide(None, 10.0, None, 1.0) == "not measured"
    assert decide(4.0, 10.0, None, 1.0) == "not resolved"
    assert decide(None, 10.0, None, 1.0, unresolved_figure=True) == "not resolved"
