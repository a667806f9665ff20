import numpy as np

from lps_gui.report.figures.axes import log_ticks, nice_ticks, padded, tick_label


def test_nice_ticks_on_1_2_5_steps_inside_the_range():
    t = nice_ticks(-3.2, 17.9, target=6)
    assert t[0] >= -3.2 and t[-1] <= 17.9
    step = np.diff(t)
    assert np.allclose(step, step[0]) and step[0] in (1.0, 2.0, 5.0, 10.0)
    assert 0.0 in t


def test_log_ticks_and_labels():
    assert log_ticks(3.0, 120.0).tolist() == [5.0, 10.0, 20.0, 50.0, 100.0]
    assert tick_label(-2.5, np.array([-5.0, -2.5, 0.0])) == "\u22122.5"


def test_flat_range_is_widened():
    lo, hi = padded(4.0, 4.0)
    assert lo < 4.0 < hi
