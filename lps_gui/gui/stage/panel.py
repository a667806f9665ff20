"""Stage panel: connection, digital readout, jogging, machine commands, $$ settings.

Every stage call goes through :class:`StageController` (one stage thread);
this widget only submits commands and shows what the controller reports.
Keyboard jog is never a side effect of typing or clicking: the arrow keys
move the stage only with the "Keyboard jog" box ticked (off at start), while
the panel has focus, and never while a number, list or text field has focus,
where they edit. The readout takes work, machine and offset of every axis
from one status report, with the WorkCoordinates capability's sign (work = machine - offset).
"""
from __future__ import annotations

import math
import time

from PySide6.QtCore import QEvent, QObject, QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QKeyEvent, QKeySequence, QShortcut
from PySide6.QtWidgets import (
    QAbstractButton,
    QAbstractItemView,
    QAbstractSpinBox,
    QApplication,
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QMessageBox,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from lps_gui.core.clock import Clock
from lps_gui.gui.stage.console import StageConsole
from lps_gui.gui.stage.controller import StageController
from lps_gui.gui.stage.declared import show_declared, stop_action
from lps_gui.gui.stage.dro import PositionReadout
from lps_gui.gui.fit import compact_buttons
from lps_gui.gui.stage.sources import BAUD_RATES, open_stage_source, source_from_text, stage_choices
from lps_gui.hardware.capabilities import Settings, WorkCoordinates
from lps_gui.hardware.registry import DEFAULT_PORT_KIND, specs_help
from lps_gui.hardware.stage import AXES, StageSetting, StageStatus

JOG_STEPS_MM = (0.01, 0.1, 1.0, 10.0, 50.0)
CONTINUOUS = 0.0  # the "hold" step: jog while the button is pressed
HOLD_JOG_PERIOD_MS = 100  # held jog button: short jogs of v*dt queued while held, jog cancel on release
PORT_WATCH_MS = 3000  # how often the source list looks for new serial ports and emulator ptys
AXIS_SETS = (("XYZ", "X Y Z"), ("X", "X only"), ("XY", "X Y"))
JOG_KEYS = {  # key -> (axis, sign): arrows move X/Y, Page Up/Down move Z
    Qt.Key.Key_Right: ("X", +1), Qt.Key.Key_Left: ("X", -1), Qt.Key.Key_Up: ("Y", +1),
    Qt.Key.Key_Down: ("Y", -1), Qt.Key.Key_PageUp: ("Z", +1), Qt.Key.Key_PageDown: ("Z", -1),
}


class StagePanel(QWidget):
    """Connect a stage, watch its position, move it."""

    camera_offered = Signal(object)  # the simulated camera that rides the simulated stage, or None
    source_changed = Signal(object)  # the source now chosen (sim, emulator, grbl:PORT) or None: not understood
    _work_system_read = Signal(str)  # from the stage thread

    def __init__(self, controller: StageController, clock: Clock | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.clock = clock  # for the simulated rig; None: real time
        self._settings: list[StageSetting] = []

        # --- connection
        self.source = QComboBox()
        self.source.setMinimumContentsLength(14)
        self.source.setEditable(True)  # an external emulator's /dev/pts/N, a port not listed
        self.source.setInsertPolicy(QComboBox.InsertPolicy.NoInsert)
        self.source.setToolTip(f"Pick a source, or type one: {specs_help()}; a bare port (/dev/pts/5, COM3) opens as "
                               f"{DEFAULT_PORT_KIND}PORT")
        self.refresh_btn = QPushButton("Refresh")
        self.refresh_btn.setToolTip("List serial ports again")
        self.baud = QComboBox()
        for b in BAUD_RATES:
            self.baud.addItem(f"{b} baud", b)
        self.connect_btn = QPushButton("Connect")
        self.connect_btn.setDefault(True)
        conn = QGroupBox("Connection")
        g = QGridLayout(conn)
        g.addWidget(QLabel("Source"), 0, 0)
        g.addWidget(self.source, 0, 1)
        g.addWidget(self.refresh_btn, 0, 2)
        g.addWidget(QLabel("Speed"), 1, 0)
        g.addWidget(self.baud, 1, 1)
        g.addWidget(self.connect_btn, 1, 2)

        # --- digital readout
        dro = PositionReadout()
        self.dro = dro
        self.readout, self.machine, self.offset = dro.readout, dro.machine, dro.offset
        self.zero_buttons, self.to_zero_buttons = dro.zero_buttons, dro.to_zero_buttons
        self.work_system, self.state_label, self.feed_label = dro.work_system, dro.state_label, dro.feed_label
        self._axis_widgets: dict[str, list[QWidget]] = {ax: list(ws) for ax, ws in dro.axis_widgets.items()}
        self._axes_shown = "".join(AXES)
        dro.system_chosen.connect(self.select_work_system)
        dro.zero_confirmed.connect(self.zero)
        dro.to_zero_requested.connect(self.go_to_zero)

        # --- jogging
        jog = QGroupBox("Jog")
        jog.setFocusPolicy(Qt.FocusPolicy.StrongFocus)  # a click on the area takes the focus off a field
        self.jog_area = jog
        jg = QGridLayout(jog)
        self.jog_buttons: dict[tuple[str, int], QPushButton] = {}
        for r, ax in enumerate(AXES):
            for c, sign in enumerate((-1, +1)):
                b = QPushButton(f"{ax}{'−' if sign < 0 else '+'}")
                compact_buttons(b, padding=32)  # not the style's 80 px: the pad fits a 1000 px screen's dock
                b.clicked.connect(lambda _=False, a=ax, s=sign: self.jog(a, s))
                b.pressed.connect(lambda a=ax, s=sign: self._hold_jog_start(a, s))
                b.released.connect(self._hold_jog_stop)
                jg.addWidget(b, r, c)
                self.jog_buttons[(ax, sign)] = b
                self._axis_widgets[ax].append(b)
        self.step = QComboBox()
        for s in JOG_STEPS_MM:
            self.step.addItem(f"{s:g} mm", s)
        self.step.addItem("hold (continuous)", CONTINUOUS)
        self.step.setToolTip("Distance per click; 'hold': the stage moves while a jog button is held down")
        self.step.setCurrentIndex(2)
        self.step.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.step.setMinimumContentsLength(8)  # "hold (continuous)" elides in the box, whole in the list
        self.feed = QDoubleSpinBox()
        self.feed.setRange(1.0, 20000.0)
        self.feed.setDecimals(0)
        self.feed.setValue(600.0)
        self.feed.setSuffix(" mm/min")
        jg.addWidget(QLabel("Step"), 0, 2)
        jg.addWidget(self.step, 0, 3)
        jg.addWidget(QLabel("Feed"), 1, 2)
        jg.addWidget(self.feed, 1, 3)
        self.keyboard_jog = QCheckBox("Keyboard jog")
        self.keyboard_jog.setChecked(False)  # off at start: a key never moves the stage unasked
        self.keyboard_jog.setToolTip("When ticked: arrow keys jog X/Y and Page Up/Down jog Z while the stage panel "
                                     "has focus (number and list fields keep their keys)")
        self.keyboard_state = QLabel()
        keys = QHBoxLayout()  # under the pad, not in the Step/Feed column (it widened the panel past its dock)
        keys.addWidget(self.keyboard_jog)
        keys.addWidget(self.keyboard_state)
        keys.addStretch(1)
        jg.addLayout(keys, 4, 0, 1, 4)
        self.travel_label = QLabel("travel: read the settings")
        self.travel_label.setWordWrap(True)
        self.travel_label.setStyleSheet("QLabel { color: #555555; }")
        jg.addWidget(self.travel_label, 3, 0, 1, 4)
        self.axes = QComboBox()
        for key, label in AXIS_SETS:
            self.axes.addItem(label, key)
        self.axes.setToolTip("Axes shown: hide the ones a single-axis stage does not have")
        self.axes.currentIndexChanged.connect(lambda _i: self.show_axes(self.axes.currentData()))
        self._hold_timer = QTimer(self)
        self._hold_timer.setInterval(HOLD_JOG_PERIOD_MS)
        self._hold_timer.timeout.connect(self._hold_jog_step)
        self._hold_axis: tuple[str, int] | None = None
        self._hold_future: object | None = None

        # --- go to
        goto = QHBoxLayout()
        self.goto_axis = QComboBox()
        for ax in AXES:
            self.goto_axis.addItem(ax, ax)
        self.goto_target = QDoubleSpinBox()
        self.goto_target.setRange(-10000.0, 10000.0)
        self.goto_target.setDecimals(3)
        self.goto_target.setSuffix(" mm")
        self.goto_btn = QPushButton("Go to")
        self.goto_btn.setToolTip("Move to this work coordinate at the jog feed")
        self.goto_btn.clicked.connect(self.go_to)
        goto.addWidget(QLabel("Go to"))
        goto.addWidget(self.goto_axis)
        goto.addWidget(self.goto_target, 1)
        goto.addWidget(self.goto_btn)
        axes_row = QHBoxLayout()  # a row of its own: beside Go to it pushed the panel past a 1000 px screen's dock
        axes_row.addWidget(QLabel("Axes shown"))
        axes_row.addWidget(self.axes)
        axes_row.addStretch(1)

        # --- machine commands
        cmds = QGridLayout()
        self.home_btn = QPushButton("Home")
        self.unlock_btn = QPushButton("Unlock")
        self.resume_btn = QPushButton("Resume")
        self.reset_btn = QPushButton("Reset")
        self.reset_btn.setToolTip("Soft reset: stops at once; needed after a limit alarm")
        self.reset_btn.clicked.connect(self.reset)
        self.stop_btn = QPushButton("Stop (feed hold)")
        self.stop_btn.setStyleSheet("QPushButton { color: #b00020; font-weight: bold; }")
        self.stop_btn.setToolTip("Esc: cancels a jog, or holds a programmed move (feed hold). "
                                 "Resume continues the move; Reset discards it")
        self.moved_btn = QPushButton("Moved")
        self.moved_btn.setToolTip("A stage you move by hand: press when the carriage is at the position asked for")
        self.moved_btn.clicked.connect(lambda: self.controller.call_now("moved", "confirm_moved"))
        for i, b in enumerate((self.home_btn, self.unlock_btn, self.resume_btn, self.moved_btn)):
            cmds.addWidget(b, 0, i)
        cmds.addWidget(self.stop_btn, 1, 0, 1, 2)
        cmds.addWidget(self.reset_btn, 1, 2)
        self.home_btn.clicked.connect(self.home)
        self.unlock_btn.clicked.connect(lambda: self.controller.call("unlock", "unlock"))
        self.resume_btn.clicked.connect(lambda: self.controller.call("resume", "resume"))
        self.stop_btn.clicked.connect(self.stop)

        # --- settings
        sett = QGroupBox("Controller settings ($$)")
        sl = QVBoxLayout(sett)
        self.settings_table = QTableWidget(0, 4)
        self.settings_table.setHorizontalHeaderLabels(["#", "Setting", "Value", "Unit"])
        self.settings_table.verticalHeader().setVisible(False)
        self.settings_table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        hh = self.settings_table.horizontalHeader()
        hh.setSectionResizeMode(1, QHeaderView.ResizeMode.Stretch)
        for col in (0, 2, 3):
            hh.setSectionResizeMode(col, QHeaderView.ResizeMode.ResizeToContents)
        row = QHBoxLayout()
        self.read_settings_btn = QPushButton("Read")
        self.write_settings_btn = QPushButton("Write changes")
        row.addWidget(self.read_settings_btn)
        row.addWidget(self.write_settings_btn)
        row.addStretch(1)
        sl.addWidget(self.settings_table)
        sl.addLayout(row)
        self.read_settings_btn.clicked.connect(self.controller.read_settings)
        self.write_settings_btn.clicked.connect(self.write_settings)

        lay = QVBoxLayout(self)
        lay.setContentsMargins(6, 6, 6, 6)
        lay.addWidget(conn)
        lay.addWidget(dro)
        lay.addWidget(jog)
        lay.addLayout(goto)
        lay.addLayout(axes_row)
        lay.addLayout(cmds)
        self.console = StageConsole(controller)
        self.lower_tabs = QTabWidget()  # settings and console share the space: the panel stays short
        sett.setTitle("")
        self.settings_page = sett
        self.lower_tabs.addTab(sett, "Settings")
        self.lower_tabs.addTab(self.console, "Console")
        lay.addWidget(self.lower_tabs, 1)

        self.source.currentTextChanged.connect(lambda _t: self.source_changed.emit(self.current_source()))
        self.refresh_btn.clicked.connect(lambda _checked=False: self.refresh_sources())  # clicked(bool) is no list
        self.connect_btn.clicked.connect(self.toggle_connection)
        controller.status_changed.connect(self.show_status)
        controller.connection_changed.connect(self._on_connection)
        controller.settings_read.connect(self.show_settings)
        controller.opened.connect(lambda _stage, extra, _d: self.camera_offered.emit(extra))
        self._work_system_read.connect(self.dro.show_system)
        self._shortcuts = []
        self._lock_box: QMessageBox | None = None
        self._lock_asked = False
        for b in self.findChildren(QAbstractButton):  # buttons take arrows for focus moves: decide first
            b.installEventFilter(self)
        self.keyboard_jog.toggled.connect(lambda _on: self._show_keyboard_state())
        app = QApplication.instance()
        if app is not None:
            app.focusChanged.connect(self._on_focus_changed)  # a method: disconnected with the panel
        self._show_keyboard_state()
        esc = QShortcut(QKeySequence(Qt.Key.Key_Escape), self, context=Qt.ShortcutContext.WidgetWithChildrenShortcut)
        esc.activated.connect(self.stop)
        self._shortcuts.append(esc)
        self._choices: list[tuple[str, str]] = []
        self.refresh_sources()
        self._port_timer = QTimer(self)
        self._port_timer.setInterval(PORT_WATCH_MS)
        self._port_timer.timeout.connect(self._watch_ports)
        self._port_timer.start()
        self._set_enabled(False)

    # ------------------------------------------------------------------ keyboard jog
    def keyboard_jog_active(self, w: QWidget | None = None) -> bool:
        """Would a jog key pressed in ``w`` (default: the focus widget) move the stage?"""
        w = w if w is not None else QApplication.focusWidget()
        if w is None or not (w is self or self.isAncestorOf(w)):
            return False
        if isinstance(w, (QAbstractSpinBox, QComboBox, QLineEdit, QAbstractItemView)) or isinstance(
                w.parentWidget(), (QAbstractSpinBox, QComboBox)):
            return False  # the key edits the field
        return self.keyboard_jog.isChecked()

    def _jog_key(self, event: QKeyEvent) -> bool:
        """Jog for a jog key if keyboard jog is active for the focus widget; True when the key was used."""
        move = JOG_KEYS.get(Qt.Key(event.key()))
        if move is None or event.modifiers() not in (Qt.KeyboardModifier.NoModifier, Qt.KeyboardModifier.KeypadModifier):
            return False
        if not self.keyboard_jog_active():
            return False
        if not event.isAutoRepeat():  # one step per press: a held key must not queue a run of jogs
            self.jog(*move)
        return True

    def keyPressEvent(self, event: QKeyEvent) -> None:
        """Keys the focus widget ignored (the jog area, labels) end here; fields use theirs and never do.

        Only the buttons carry an event filter (they take arrows for focus moves):
        a Python filter on every widget would run for every paint event and
        compete for the GIL with the workers.
        """
        if self._jog_key(event):
            event.accept()
            return
        super().keyPressEvent(event)

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.KeyPress and self._jog_key(event):  # type: ignore[arg-type]
            return True
        return super().eventFilter(obj, event)

    def _on_focus_changed(self, _old: QWidget | None, _new: QWidget | None) -> None:
        self._show_keyboard_state()

    def _show_keyboard_state(self) -> None:
        on = self.keyboard_jog_active()
        self.keyboard_state.setText("keys jog: ON" if on else "keys jog: off")
        self.keyboard_state.setStyleSheet(
            "QLabel { color: white; background: #1f5fa8; border-radius: 3px; padding: 1px 6px; font-weight: bold; }"
            if on else "QLabel { color: #777777; }")

    # ------------------------------------------------------------------ connection
    def current_source(self) -> str | None:
        """The chosen source: a listed entry, or what was typed (``/dev/pts/5`` -> ``grbl:/dev/pts/5``)."""
        text = self.source.currentText().strip()
        i = self.source.findText(text)
        if i >= 0:
            return self.source.itemData(i)
        return source_from_text(text)

    def refresh_sources(self, choices: list[tuple[str, str]] | None = None) -> None:
        """List the sources again (serial ports, by-id names, announced emulator ptys), keeping the choice."""
        choices = stage_choices() if choices is None else choices
        current = self.current_source()
        self.source.blockSignals(True)
        self.source.clear()
        for label, src in choices:
            self.source.addItem(label, src)
        self.source.blockSignals(False)
        self._choices = choices
        if current is not None and self.source.findData(current) < 0 and ":" in current:
            self.select_source(current)  # a typed port stays
        else:
            self.source.setCurrentIndex(max(self.source.findData(current), 0))
        self.source_changed.emit(self.current_source())

    def _watch_ports(self) -> None:
        """Every few seconds while disconnected: a plugged adapter or a started emulator appears by itself."""
        if self.controller.connected or self.source.hasFocus() or self.source.view().isVisible():
            return
        choices = stage_choices()
        if choices != self._choices:
            self.refresh_sources(choices)

    def baud_rate(self) -> int:
        return int(self.baud.currentData() or 115200)

    def remember(self, s: QSettings) -> None:
        """Keep the source and speed that connected, for the next start."""
        s.setValue("stage/source", self.current_source())
        s.setValue("stage/baud", self.baud_rate())

    def restore(self, s: QSettings) -> None:
        source = s.value("stage/source")
        if source:
            self.select_source(str(source))  # the simulated stage is the default otherwise
        baud = s.value("stage/baud")
        i = self.baud.findData(int(baud)) if baud is not None else -1
        if i >= 0:
            self.baud.setCurrentIndex(i)

    def select_source(self, source: str) -> None:
        i = self.source.findData(source)
        if i < 0 and ":" in source:  # a typed port or argument (grbl:/dev/pts/5, command:...)
            self.source.addItem(source.split(":", 1)[1], source)
            i = self.source.count() - 1
        self.source.setCurrentIndex(max(i, 0))
        self.source.setEditText(self.source.itemText(max(i, 0)))

    def toggle_connection(self) -> None:
        if self.controller.connected:
            if time.monotonic() - getattr(self, "_connect_at", -1e9) < QApplication.doubleClickInterval() / 1000:
                return  # the second click of a double-click on Connect: the stage connected meanwhile, keep it
            self.controller.detach("disconnected by the operator")
        else:
            self._connect_at = time.monotonic()
            self.connect_source()

    def connect_source(self) -> None:
        src = self.current_source()
        if src is None:
            self.controller.command_failed.emit(
                "connect", f"stage source {self.source.currentText()!r} not understood; pick one or type a port such as /dev/ttyUSB0")
            return
        baud = self.baud_rate()
        self.connect_btn.setEnabled(False)
        self.connect_btn.setText("Connecting…")
        clock = self.clock
        self.controller.open(lambda: open_stage_source(src, baud, clock), self.source.currentText())

    def _on_connection(self, connected: bool, description: str) -> None:
        self.connect_btn.setEnabled(True)
        self.connect_btn.setText("Disconnect" if connected else "Connect")
        self.source.setEnabled(not connected)
        self.baud.setEnabled(not connected)
        self._set_enabled(connected)
        self._lock_asked = False
        if connected:
            if isinstance(self.controller.stage, Settings):
                self.controller.read_settings()
            self._read_work_system()
        else:
            self.dro.clear()

    def connect_failed(self) -> None:
        """The controller could not open the source: offer Connect again."""
        self._on_connection(False, "")

    def _set_enabled(self, on: bool) -> None:
        for b in list(self.jog_buttons.values()) + list(self.to_zero_buttons.values()) + [
                self.home_btn, self.unlock_btn, self.resume_btn, self.stop_btn, self.read_settings_btn,
                self.write_settings_btn, self.goto_btn, self.reset_btn]:
            b.setEnabled(on)
        show_declared(self, self.controller.stage if on else None, on)

    # ------------------------------------------------------------------ readout
    def show_status(self, st: StageStatus) -> None:
        self.dro.show_status(st)
        if st.state == "Alarm" and not self._lock_asked:
            self._lock_asked = True
            self._ask_home_or_unlock()
        elif st.state != "Alarm":
            self._lock_asked = False  # a later alarm asks again

    def _ask_home_or_unlock(self) -> None:
        """A stage in Alarm (a controller with homing enabled may power up so) moves only once homed or unlocked: ask which."""
        hint = getattr(self.controller.stage, "lock_hint", "home it or unlock it")
        box = QMessageBox(QMessageBox.Icon.Question, "Stage locked",
                          "The stage is locked in Alarm (at power-up with homing enabled, and after an alarm).\n"
                          f"Home or unlock it ({hint})? Homing drives to the limit switch; unlocking keeps the "
                          "position it believes.\nAfter a limit alarm press Reset first.",
                          parent=self)
        home = box.addButton("Home", QMessageBox.ButtonRole.AcceptRole)
        unlock = box.addButton("Unlock", QMessageBox.ButtonRole.ActionRole)
        box.addButton("Not now", QMessageBox.ButtonRole.RejectRole)
        home.clicked.connect(self.home)
        unlock.clicked.connect(lambda: self.controller.call("unlock", "unlock"))
        box.open()
        self._lock_box = box

    # ------------------------------------------------------------------ motion
    def home(self) -> None:
        """``$H``: shown as Home at once (the cycle may run for a minute); the controller logs its end."""
        if self.controller.call("home", "home") is not None:
            self.dro.show_state("Home")

    def jog(self, axis: str, sign: int) -> None:
        if not self.controller.connected:
            return
        step_mm = float(self.step.currentData())
        if step_mm == CONTINUOUS:
            if self._hold_axis is None:  # a key press: one 1 mm step (a key has no release to stop on)
                self.controller.call(f"jog {axis} {sign:+g} mm", "jog", float(sign), self.feed.value(), axis)
            return
        self.controller.call(f"jog {axis} {sign * step_mm:+g} mm", "jog", sign * step_mm, self.feed.value(), axis)

    def _hold_jog_start(self, axis: str, sign: int) -> None:
        if float(self.step.currentData()) != CONTINUOUS or not self.controller.connected:
            return
        self._hold_axis = (axis, sign)
        self._hold_future = None
        self._hold_jog_step()
        self._hold_timer.start()

    def _hold_jog_step(self) -> None:
        """Queue the next short jog (v * dt) once the last one is planned: at most one waits on our side."""
        if self._hold_axis is None:
            return
        fut = self._hold_future
        if fut is not None and not fut.done():  # type: ignore[attr-defined]
            return
        if fut is not None and fut.exception() is not None:  # type: ignore[attr-defined]
            self._hold_jog_stop()  # e.g. error:15 at the end of the travel
            return
        axis, sign = self._hold_axis
        feed = self.feed.value()
        step = sign * feed / 60.0 * HOLD_JOG_PERIOD_MS / 1000.0 * 1.5  # a little ahead: no stutter between jogs
        self._hold_future = self.controller.call(f"jog {axis} {step:+.3f} mm (held)", "jog", step, feed, axis)

    def _hold_jog_stop(self) -> None:
        if self._hold_axis is None:
            return
        self._hold_axis = None
        self._hold_timer.stop()
        self.controller.call_now("jog cancel", "jog_cancel")

    # ------------------------------------------------------------------ work coordinates
    def _read_work_system(self) -> None:
        stage = self.controller.stage
        if not isinstance(stage, WorkCoordinates) or not stage.work_systems:
            self.work_system.setCurrentIndex(0)
            return
        fut = self.controller.call("read the work coordinate system", "work_system")
        if fut is not None:
            fut.add_done_callback(lambda f: None if f.exception() else self._work_system_read.emit(f.result()))

    def select_work_system(self, name: str) -> None:
        """Make ``name`` (G54-G59) the system the readout, Go to and Zero use."""
        if self.controller.call(f"select work system {name}", "select_work_system", name) is not None:
            self.dro.show_system(name)

    def zero(self, axis: str) -> None:
        system = self.work_system.currentData()
        self.controller.call(f"zero {axis} in {system} (work offset)", "set_work_zero", axis)

    def go_to_zero(self, axis: str) -> None:
        self.controller.call(f"go to {axis} 0 ({self.work_system.currentData()})", "move_to", 0.0, self.feed.value(), axis)

    def reset(self) -> None:
        """Soft reset: what a feed hold cannot do, discard the held move; the stage may then need unlocking."""
        self.controller.call_now("reset", "soft_reset")

    def go_to(self) -> None:
        axis = self.goto_axis.currentData()
        target = self.goto_target.value()
        self.controller.call(f"go to {axis} {target:.3f} mm", "move_to", target, self.feed.value(), axis)

    def show_axes(self, axes: str) -> None:
        """Show only ``axes`` (e.g. "X" for a single-axis stage) in the readout, the jog pad and go-to."""
        self._axes_shown = axes
        for ax, widgets in self._axis_widgets.items():
            for w in widgets:
                w.setVisible(ax in axes)
        for i in range(self.goto_axis.count()):
            self.goto_axis.model().item(i).setEnabled(self.goto_axis.itemData(i) in axes)  # type: ignore[attr-defined]
        if self.goto_axis.currentData() not in axes:
            self.goto_axis.setCurrentIndex(self.goto_axis.findData(axes[0]))

    def stop(self) -> None:
        """Stop motion now: cancel a jog; a programmed move is held (Resume continues it)."""
        st = self.controller.last_status
        action = stop_action(self.controller.stage, st is not None and st.state == "Run")
        if action is not None:
            self.controller.call_now(*action)

    # ------------------------------------------------------------------ settings
    def show_settings(self, settings: list[StageSetting]) -> None:
        self._settings = list(settings)
        stage = self.controller.stage
        self.travel_label.setText(stage.travel_text(settings) if isinstance(stage, Settings) else "travel: unknown")
        t = self.settings_table
        t.setRowCount(len(settings))
        for r, s in enumerate(settings):
            label = self._setting_label(s)
            for c, text in enumerate((label, s.name, f"{s.value:g}", s.unit)):
                item = QTableWidgetItem(text)
                if c != 2:
                    item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsEditable)
                if s.description:
                    item.setToolTip(s.description)
                t.setItem(r, c, item)

    def _setting_label(self, s: StageSetting) -> str:
        """The setting as its controller names it (GRBL ``$110``, Marlin ``M203 X``): the stage's declaration says."""
        stage = self.controller.stage
        return stage.setting_label(s) if isinstance(stage, Settings) else str(s.number)

    def pending_settings(self) -> tuple[list[tuple[int, float]], list[str]]:
        """Edited values as (number, value), and one line per value that fails validation."""
        changes, errors = [], []
        for r, s in enumerate(self._settings):
            label = self._setting_label(s)
            item = self.settings_table.item(r, 2)
            text = item.text().strip() if item else ""
            try:
                value = float(text)
            except ValueError:
                errors.append(f"{label} ({s.name}): {text!r} is not a number")
                continue
            if not math.isfinite(value) or value < 0:
                errors.append(f"{label} ({s.name}): must be a finite value ≥ 0")
            elif _is_integer_setting(s) and value != int(value):
                errors.append(f"{label} ({s.name}): must be a whole number")
            elif value != s.value:
                changes.append((s.number, value))
        return changes, errors

    def write_settings(self) -> None:
        changes, errors = self.pending_settings()
        if errors:
            box = QMessageBox(QMessageBox.Icon.Warning, "Settings not written", "\n".join(errors), parent=self)
            box.open()
            self._last_box = box
            return
        for number, value in changes:
            self.controller.write_setting(number, value)
        if changes:
            self.controller.read_settings()


def _is_integer_setting(s: StageSetting) -> bool:
    unit = (s.unit or "").lower()
    return unit in ("mask", "boolean", "bool", "") and float(s.value).is_integer() and "mm" not in unit

