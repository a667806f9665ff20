"""Smaller GUI items of issue 26 (item 12): compact angular legend, readable log ticks, the ISO 230-2 default plan."""
from __future__ import annotations

import pytest

from lps_gui.gui.results.plot_adapter import ReadableAxis, component_name

pytestmark = pytest.mark.gui


def test_a_twelve_series_legend_names_each_component_and_style_once(qtbot, window):
    from tests.report.conftest import make_results

    results, truth = make_results()
    results = {**results, "truth": truth}  # truth series too: 9 or more in the angles figure
    rp = window.results_panel
    with qtbot.waitSignal(rp.drawing_done, timeout=20000):
        rp.set_results(results, None, None)
    spec = rp.drawn["angles"].spec
    legend = rp.plots["angles"].getPlotItem().legend
    labels = [label.text for _sample, label in legend.items]
    assert len(spec.series) >= 9 and len(labels) <= 7
    assert {"roll", "pitch", "yaw"} <= set(labels) and any(t.startswith("forward") for t in labels)
    assert component_name("pitch backward \u2193") == "pitch" and component_name("truth image rotation") == "image rotation"


def test_log_ticks_read_as_plain_numbers(qtbot):
    axis = ReadableAxis("bottom")
    axis.setLogMode(True)
    assert axis.tickStrings([1.0, 1.30103, 1.47712, 1.69897, 2.0], 1.0, 1.0) == ["10", "20", "", "50", "100"]


def test_the_default_plan_is_iso_230_2_with_the_preset_first(window):
    cap = window.capture_panel
    plan = cap.plan()
    assert plan.directions == "both" and plan.runs == 5
    form = cap.iso_btn.parentWidget().layout()
    assert form.itemAt(0, form.ItemRole.LabelRole).widget().text() == "Preset"
