"""The stage panel shows what the connected stage declares, nothing more (docs/hardware.md, capabilities).

A stage without settings has no settings tab, one without a console no
console tab, one that cannot jog no jog pad; a stage the operator moves by
hand has a "Moved" button. The panel asks the declarations
(:mod:`lps_gui.hardware.capabilities`), never which protocol is connected.
"""
from __future__ import annotations

from typing import Any

from lps_gui.hardware.capabilities import Alarms, Console, FeedHold, Jogging, OperatorMoved, Settings, WorkCoordinates


def show_declared(panel: Any, stage: Any, on: bool) -> None:
    """Show and enable ``panel``'s widgets for what ``stage`` declares (all of them while nothing is connected)."""
    known = stage is not None

    def has(cap: type) -> bool:
        return not known or isinstance(stage, cap)

    panel.jog_area.setVisible(has(Jogging))
    for b in (panel.unlock_btn, panel.reset_btn):
        b.setVisible(has(Alarms))
    panel.resume_btn.setVisible(has(FeedHold))
    panel.home_btn.setEnabled(on and bool(getattr(stage, "can_home", False)))
    panel.moved_btn.setVisible(known and isinstance(stage, OperatorMoved))
    panel.moved_btn.setEnabled(on and isinstance(stage, OperatorMoved))
    tabs = panel.lower_tabs
    tabs.setTabVisible(tabs.indexOf(panel.settings_page), has(Settings))
    tabs.setTabVisible(tabs.indexOf(panel.console), has(Console))
    tabs.setVisible(has(Settings) or has(Console))
    if known and isinstance(stage, Settings):
        tabs.setTabText(tabs.indexOf(panel.settings_page), stage.settings_title)
    panel.dro.set_offsets_enabled(on and known and isinstance(stage, WorkCoordinates) and bool(stage.work_systems))


def stop_action(stage: Any, running: bool) -> tuple[str, str] | None:
    """(what, method) the Stop button calls on ``stage``: a feed hold of a running move, a jog cancel, else stop."""
    if running and isinstance(stage, FeedHold):
        return "feed hold", "feed_hold"
    if isinstance(stage, Jogging):
        return "jog cancel", "jog_cancel"
    return ("stop", "stop") if stage is not None else None
