"""Painting must not eat Python's references to None.

PySide6 6.12.0 returns None from void C++ methods without taking a reference;
on Python < 3.12 every QPainter call then drops one, and a long report or an
hour of live plots aborts the interpreter (none_dealloc). pyproject pins
PySide6 below 6.12; these tests fail if a release with the bug comes back.
"""
from __future__ import annotations

import sys

import pytest

from tests.report.conftest import make_results


@pytest.mark.gui
def test_void_painter_calls_keep_none_alive():
    from PySide6.QtGui import QImage, QPainter, QPen

    image = QImage(8, 8, QImage.Format_RGB32)
    painter = QPainter(image)
    pen = QPen()
    before = sys.getrefcount(None)
    for _ in range(2000):
        painter.setPen(pen)
    after = sys.getrefcount(None)
    painter.end()
    assert after >= before - 50, f"PySide6 lost {before - after} references to None in 2000 calls"


@pytest.mark.gui
def test_a_long_report_leaves_none_references_intact(tmp_path):
    from lps_gui.report.pdf.document import write_report

    results, truth = make_results(runs=2, views=60)
    before = sys.getrefcount(None)
    write_report(tmp_path, results, tmp_path / "r.pdf")
    assert sys.getrefcount(None) >= before - 50  # unrelated objects may come and go
