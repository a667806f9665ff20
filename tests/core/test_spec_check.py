"""Straight-line accuracy against a data sheet must not blame the stage for measurement noise."""
from lps_gui.core.metrology.iso230 import check_specification


def straightness_row(span_um, sigma_um):
    figures = {"straightness_um_max": span_um, "straightness_sigma_um": sigma_um}
    (row,) = check_specification(figures, {"straightness_um": 38.0})
    return row


def test_a_span_within_the_limit_passes_even_when_noisy():
    assert straightness_row(30.0, 20.0)["passed"] is True


def test_a_span_over_the_limit_fails_when_noise_cannot_explain_it():
    assert straightness_row(60.0, 2.0)["passed"] is False


def test_a_span_over_the_limit_is_not_resolved_when_noise_alone_spans_it():
    row = straightness_row(200.0, 30.0)
    assert row["passed"] is None and "not resolved" in row["note"]
