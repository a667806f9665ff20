"""Qt calls the GUI makes all the time must not eat references to None, True or False.

PySide6 6.12.0 on Python < 3.12 gives back a reference to None on every void
call: a readout repainting a few times a second aborts the interpreter within
minutes (none_dealloc). pyproject pins PySide6 below 6.12; this fails if a
release with that bug is installed.
"""
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def counts():
    return {name: sys.getrefcount(obj) for name, obj in (("None", None), ("True", True), ("False", False))}


def test_readout_and_preview_calls_keep_singletons_alive(qtbot):
    import pyqtgraph as pg
    from PySide6.QtWidgets import QLabel, QProgressBar, QPushButton

    label, bar, button = QLabel(), QProgressBar(), QPushButton()
    image = pg.ImageItem()
    frame = np.zeros((48, 64), dtype=np.uint8)
    for w in (label, bar, button):
        qtbot.addWidget(w)
    before = counts()
    for i in range(2000):
        label.setText(f"{i:.3f} mm")
        bar.setValue(i % 100)
        button.setEnabled(i % 2 == 0)
        image.setImage(frame, autoLevels=False)
    after = counts()
    for name in before:
        assert after[name] >= before[name] - 50, f"lost {before[name] - after[name]} references to {name} in 2000 calls"
