"""Skew and backlash lines checked against the controllers' own formulas."""
from __future__ import annotations

import math

import numpy as np
import pytest

from lps_gui.core.metrology.compensation import CompensationTable
from lps_gui.errors import InputError
from lps_gui.io.compensation_file import backlash_lines, mach4_text, read_table, skew_lines


def klipper_skew_factor(ac: float, bd: float, ad: float) -> float:
    """Klipper's skew_correction.calc_skew_factor (and Marlin's _SKEW_FACTOR), as documented."""
    side = math.sqrt(2 * ac * ac + 2 * bd * bd - 4 * ad * ad) / 2.0
    return math.tan(math.pi / 2 - math.acos((ac * ac - side * side - ad * ad) / (2 * side * ad)))


@pytest.mark.parametrize("urad", [-800.0, 0.0, 150.0, 2500.0])
def test_skew_lines_round_trip_through_klipper_formula(urad):
    lines = skew_lines(urad, side_mm=100.0)
    ac, bd, ad = (float(v) for v in lines[0].split()[1].removeprefix("XY=").split(","))
    factor = math.tan(urad * 1e-6)
    assert klipper_skew_factor(ac, bd, ad) == pytest.approx(factor, abs=2e-6)  # 4 decimals of the lengths
    assert float(lines[1].split()[1][1:]) == pytest.approx(factor, abs=1e-6)
    assert lines[2].startswith("M556 S100 X") and float(lines[2].split()[2][1:]) == pytest.approx(100 * factor, abs=1e-4)


def test_backlash_lines():
    grbl, marlin = backlash_lines(12.3, "Y")
    assert grbl.startswith("$161=0.0123") and marlin.startswith("M425 F1 Y0.0123")
    assert backlash_lines(-3.0)[0].startswith("$160=0.0000")  # negative reversal: nothing to add
    with pytest.raises(InputError):
        backlash_lines(1.0, "A")


def test_mach4_and_reader(tmp_path):
    x = np.linspace(0, 10, 6)
    t = CompensationTable(x, x + 0.002, x - 0.001, np.full(6, 0.1), np.full(6, 0.1), True)
    text = mach4_text(t)
    assert "# number_of_points 6" in text and "# length 10.000000" in text
    assert text.splitlines()[-1].split() == ["10.000000", "-0.002000", "0.001000"]
    (tmp_path / "off.comp").write_text("".join(f"{a} 0.002 -0.001\n" for a in x))
    back = read_table(tmp_path / "off.comp")
    np.testing.assert_allclose(back.actual_plus_mm, x + 0.002)
    (tmp_path / "bad.comp").write_text("1 2\n")
    with pytest.raises(InputError, match="3 numbers"):
        read_table(tmp_path / "bad.comp")
