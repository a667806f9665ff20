"""Issue 39's campaign, the remainder: cases the first pass left open, each failing on the code before its fix."""
from __future__ import annotations

import pytest

from lps_gui.errors import DegenerateGeometryError, LpsError


@pytest.mark.parametrize("k", [1e-300, 0.01])
def test_every_view_flagged_as_an_outlier_is_one_line_not_a_crash(point_session, k):
    from lps_gui.core.estimator.estimate_types import EstimateOptions
    from lps_gui.pipeline.estimate import estimate_session

    with pytest.raises(DegenerateGeometryError) as exc:  # the API takes any positive k (the CLI and GUI: k >= 1, 2)
        estimate_session(point_session, options=EstimateOptions(outlier_k=k))
    assert str(exc.value).startswith(f"{point_session / 'corners.vnl'}: fewer than 3 views are left after removing "
                                     "outliers (") and "raise the outlier threshold k" in str(exc.value)
    assert "\n" not in str(exc.value) and isinstance(exc.value, LpsError)
    assert not (point_session / "results.json").exists()
