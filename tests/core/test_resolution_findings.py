"""One rule decides whether a max |angle| is a finding (issue 35: "Max |roll| 204 +- 98 urad" on page 1
while the error-motion page said roll is not resolved)."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.metrology.resolution import max_abs_resolution, profile_span, with_profile_resolution


def _views(n: int = 50):
    rng = np.random.default_rng(1)
    target = np.arange(float(n))
    return target, rng.normal(0.0, 100.0, n), np.full(n, 100.0), np.ones(n, bool)


def test_a_lone_spike_over_the_noise_max_is_no_finding_when_its_profile_is_flat():
    target, values, sigma, valid = _views()
    values[17] = 420.0  # above the noise max of 50 views (~3.7 sigma), but the profile is flat at p = 0.001
    r = max_abs_resolution(values, sigma, target, valid)
    assert r["measured_max_abs_urad"] == pytest.approx(420.0 - values.mean())  # about the mean attitude
    assert r["measured_max_abs_urad"] > r["noise_max_abs_urad"]
    assert not profile_span(values, sigma, target, valid).resolved
    assert r["resolved"] is False  # the old rule (max against noise max alone) called it a finding


def test_a_real_angle_profile_is_a_finding_and_the_error_motions_verdict_can_veto_it():
    target, values, sigma, valid = _views()
    values = values + 800.0 * np.sin(target / 8.0)
    r = max_abs_resolution(values, sigma, target, valid)
    assert r["resolved"] is True
    vetoed = with_profile_resolution({"roll": r, "yaw": dict(r)}, {"roll": False})
    assert vetoed["roll"]["resolved"] is False and vetoed["yaw"]["resolved"] is True
    assert max_abs_resolution(values, sigma, target, np.zeros(50, bool)) is None


def test_summary_csv_keeps_no_span_of_an_angle_that_is_not_resolved():
    from lps_gui.io.results.document import summary_csv_rows

    figures = {"angles_span_urad": {"roll": 316.8, "yaw": 34.9},
               "angles_resolution": {"roll": {"max_abs_urad": 169.0, "noise_max_abs_urad": 215.0, "resolved": False},
                                     "yaw": {"max_abs_urad": 40.0, "noise_max_abs_urad": 19.0, "resolved": True}}}
    rows = {r[0]: r[1] for r in summary_csv_rows({"figures": figures})}
    assert rows["roll_span"] is None and rows["yaw_span"] == 34.9


def test_max_abs_angle_does_not_depend_on_the_boards_mount():
    """A camera cannot see the stage's nominal attitude: an angle's zero is the estimate's common orientation,
    which the board's mount (and, on the campaign's motions stage, the line model's misfit: ~245 urad of roll)
    shifts alike for every stop. Max |angle| and its U must not move with it (on main: max |x + c|)."""
    target, values, sigma, valid = _views()
    values = values + 800.0 * np.sin(target / 8.0)
    r = max_abs_resolution(values, sigma, target, valid)
    shifted = max_abs_resolution(values + 300.0, sigma, target, valid)
    for key in ("max_abs_urad", "u_max_abs_urad", "noise_max_abs_urad"):
        assert shifted[key] == pytest.approx(r[key], rel=1e-6, abs=1e-6), key
    assert shifted["resolved"] == r["resolved"]
