"""The render's square-wave phase (render._mod2, x - 2 floor(x / 2)) is np.mod(x, 2.0) to the bit.

Why it matters: every pixel of every simulated image goes through it; it replaced np.mod for speed and
must not move a single grey level (the simulator's truth and every recorded session stay as they were).
"""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.camera.render import _mod2, _triangle


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_the_phase_and_the_triangle_are_np_mod_s_own_numbers(dtype):
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.standard_normal(200_000) * scale for scale in (1e-3, 1.0, 40.0, 1e4, 1e7)]).astype(dtype)
    whole = np.round(x)
    x = np.concatenate([x, whole, np.nextafter(whole, dtype(np.inf)), np.nextafter(whole, dtype(-np.inf)),
                        np.array([0.0, -0.0, 2.0, -2.0, 1.0, -1.0, np.nan], dtype)])
    normal = (np.abs(x) >= np.finfo(dtype).tiny) | (x == 0) | np.isnan(x)
    assert (~normal).sum() > 1000  # the next float below a whole 0 is subnormal: the triangle is checked there too
    assert np.array_equal(_mod2(x[normal]), np.mod(x[normal], 2.0), equal_nan=True)
    assert _mod2(x).dtype == x.dtype
    # a negative subnormal's phase is itself where np.mod rounds it to 2; the triangle is the same (0) either way
    assert np.array_equal(_triangle(x), 1.0 - np.abs(np.mod(x, 2.0) - 1.0), equal_nan=True)
