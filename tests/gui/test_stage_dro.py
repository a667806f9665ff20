"""The digital readout (issue 26 item 7): one status report per update, GRBL's offset sign, G54-G59, zero and return."""
from __future__ import annotations

import pytest

from tests.gui.conftest import connect_sim

pytestmark = pytest.mark.gui


def _dro(panel, axis="X") -> tuple[float, float, float]:
    """Work, machine, offset as shown (NaN before the first report)."""
    return tuple(float(t) if (t := d[axis].text().strip()) != "---" else float("nan")
                 for d in (panel.readout, panel.machine, panel.offset))


def _confirm_zero(qtbot, panel, axis: str) -> None:
    panel.zero_buttons[axis].click()
    box = panel.dro.zero_box
    assert box is not None and panel.work_system.currentData() in box.text()
    box.button(box.StandardButton.Yes).click()


def test_work_machine_and_offset_come_from_one_report_while_moving(qtbot, window):
    connect_sim(qtbot, window)
    panel, ctl = window.stage_panel, window.stage_ctl
    panel.step.setCurrentIndex(panel.step.findData(10.0))
    panel.feed.setValue(3000.0)
    panel.jog_buttons[("X", +1)].click()
    qtbot.waitUntil(lambda: ctl.last_status.state == "Idle" and ctl.last_status.machine_mm[0] > 9.0, timeout=10000)
    _confirm_zero(qtbot, panel, "X")  # a non-zero offset, so work and machine differ
    qtbot.waitUntil(lambda: abs(_dro(panel)[0]) < 1e-9, timeout=5000)
    samples = []

    def record(st) -> None:  # runs after the panel showed this same report
        samples.append((st, _dro(panel)))

    ctl.status_changed.connect(record)
    panel.step.setCurrentIndex(panel.step.findData(50.0))
    panel.feed.setValue(600.0)  # 5 s of motion: about 25 reports, at least a few on a loaded machine
    panel.jog_buttons[("X", +1)].click()
    qtbot.waitUntil(lambda: len([s for s, _ in samples if s.state == "Jog"]) >= 4, timeout=10000)
    qtbot.waitUntil(lambda: samples[-1][0].state == "Idle", timeout=10000)
    ctl.status_changed.disconnect(record)
    moving = [(st, dro) for st, dro in samples if st.state == "Jog"]
    assert len({dro[0] for _, dro in moving}) >= 3  # the readout moved through several positions
    for st, (work, machine, offset) in moving:
        assert work == pytest.approx(st.work_mm[0], abs=5e-4) and machine == pytest.approx(st.machine_mm[0], abs=5e-4)
        assert machine - offset == pytest.approx(work, abs=2e-3)  # GRBL: work = machine - offset
    assert offset == pytest.approx(10.0, abs=1e-3) and offset > 0  # zeroed at machine +10: $# would say +10


def test_work_system_selector_zero_and_return_to_zero(qtbot, window):
    connect_sim(qtbot, window)
    panel, ctl = window.stage_panel, window.stage_ctl
    stage = ctl.stage
    panel.goto_target.setValue(20.0)
    panel.feed.setValue(3000.0)
    panel.goto_btn.click()
    qtbot.waitUntil(lambda: ctl.last_status.state == "Idle" and abs(_dro(panel)[0] - 20.0) < 1e-9, timeout=10000)
    panel.work_system.setCurrentIndex(panel.work_system.findData("G56"))
    panel.work_system.activated.emit(panel.work_system.currentIndex())
    qtbot.waitUntil(lambda: stage.work_system() == "G56", timeout=5000)
    panel.zero_buttons["X"].click()
    box = panel.dro.zero_box
    assert "G56" in box.windowTitle() and "G56 offset" in box.text()
    box.button(box.StandardButton.Cancel).click()  # cancelled: nothing changes
    qtbot.wait(200)
    assert stage.work_offsets()["G56"] == (0.0, 0.0, 0.0)
    _confirm_zero(qtbot, panel, "X")
    qtbot.waitUntil(lambda: stage.work_offsets()["G56"][0] == pytest.approx(20.0), timeout=5000)
    assert stage.work_offsets()["G54"] == (0.0, 0.0, 0.0)  # only the named system changed
    panel.goto_target.setValue(7.5)
    panel.goto_btn.click()
    qtbot.waitUntil(lambda: ctl.last_status.state == "Idle" and abs(_dro(panel)[1] - 27.5) < 1e-9, timeout=10000)
    panel.to_zero_buttons["X"].click()  # back to the work zero of G56
    qtbot.waitUntil(lambda: ctl.last_status.state == "Idle" and abs(_dro(panel)[0]) < 1e-9, timeout=10000)
    assert _dro(panel) == pytest.approx((0.0, 20.0, 20.0))
