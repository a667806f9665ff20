"""Back-end modules the GUI imports once at start-up.

The long jobs import these lazily (``--help`` and tests stay fast), but
importing a compiled extension holds the GIL for tens of milliseconds; done in
a worker thread mid-job it would freeze the window, so the window imports
them once when it opens. Plain imports, so the layer test sees every one.
"""
from __future__ import annotations


def preload_backends() -> None:
    """Import the estimator, detection, capture, report and the scipy/cv2 extensions they use."""
    import cv2  # noqa: F401
    import scipy.interpolate  # noqa: F401
    import scipy.ndimage  # noqa: F401
    import scipy.optimize  # noqa: F401
    import scipy.signal  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401
    import scipy.stats  # noqa: F401

    import lps_gui.camera.detection  # noqa: F401
    import lps_gui.capture.engine  # noqa: F401
    import lps_gui.core.estimator.estimate  # noqa: F401
    import lps_gui.core.metrology.iso230  # noqa: F401
    import lps_gui.io.results.document  # noqa: F401
    import lps_gui.pipeline.detect  # noqa: F401
    import lps_gui.pipeline.estimate  # noqa: F401
    import lps_gui.pipeline.intrinsics  # noqa: F401
    import lps_gui.report.pages.summary  # noqa: F401
    import lps_gui.sim.session  # noqa: F401
