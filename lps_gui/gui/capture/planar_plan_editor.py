"""The capture panel's planar (XY) mode: grid editor, visiting order drawn, rig prediction, simulated gantry.

A planar plan (SPEC 10) is a grid (start, stop, step as X, Y; serpentine or
raster) or the ISO 230-2 lines preset on that grid; directions, runs,
overshoot, settle, frames and feed are the capture panel's shared fields.
The plot shows the grid nodes and the order the forward pass visits them
(a path with arrows and the first stops numbered; a backward pass runs it in
reverse). The readout below is :func:`lps_gui.core.planning.rig.predict_rig`
for the plan: whether the board stays in view everywhere and the position
sigma to expect, before anything moves. "Simulated gantry" captures on a
simulated XY stage built for the plan (its camera centred over the grid),
with its truth recorded, so a planar session needs no hardware.
"""
from __future__ import annotations

import logging
from typing import Any, Callable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QLabel,
    QPushButton,
    QSizePolicy,
    QVBoxLayout,
    QWidget,
)

from lps_gui.core.planning.plan import PATTERNS, Plan, iso_lines_on_grid
from lps_gui.errors import InputError
from lps_gui.gui.widgets import add_rows, double_spin

log = logging.getLogger(__name__)

GANTRY_OFF = ""
GANTRY_PRESETS = (("Connected stage and camera", GANTRY_OFF), ("Simulated gantry (small-planar)", "small-planar"),
                  ("Simulated gantry (paper-planar)", "paper-planar"))
MAX_ARROWS = 80  # arrows along the path; beyond this the path alone shows the order
MAX_NUMBERS = 40  # stops numbered on the plot
MAX_PREDICTED_TARGETS = 3000  # the rig prediction is skipped for larger plans (a readout, not a job)
NOISE_PX = 0.1  # corner noise the prediction assumes by default (the paper's rig)
ISO_LEVELS, ISO_RUNS = 3, 5  # the ISO 230-2 lines preset: 3 lines per axis, 5 runs (as `lps capture --iso-lines`)
SHARED_FIELDS = ("directions", "runs", "overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min")


def planar_duration_s(plan: Plan, accel_mm_s2: float = 200.0, grab_s: float = 0.05) -> float:
    """Rough stage time of a planar plan (s): each axis moves on its own at the feed, plus settles and grabs."""
    from lps_gui.hardware.motion import duration_s

    total = 0.0
    for direction in plan.run_directions():
        t = plan.targets() if direction == "+" else plan.targets()[::-1]
        moves = np.abs(np.diff(np.vstack([t[:1] - plan.overshoot_mm, t]), axis=0)).ravel()
        total += sum(duration_s(float(d), plan.feed_mm_min, accel_mm_s2) for d in moves if d > 0)
    n_stops = len(plan.targets()) * len(plan.run_directions())
    return plan.runs * (total + n_stops * (plan.settle_s + plan.frames_per_stop * grab_s))


def visiting_path(plan: Plan) -> np.ndarray:
    """The forward pass' targets in visiting order, shape (m, 2) mm."""
    return plan.targets()


class PlanarPlanEditor(QGroupBox):
    """Grid fields, the visiting-order plot and the rig prediction of a planar plan."""

    changed = Signal()  # any field changed: the capture panel refreshes its summary

    def __init__(self, shared: Callable[[], dict[str, Any]], board: Callable[[], Any],
                 intrinsics: Callable[[], Any], set_shared: Callable[[dict[str, Any]], None] | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__("Planar plan (XY)", parent)
        self.shared = shared  # the capture panel's shared plan fields
        self.set_shared = set_shared or (lambda fields: None)
        self.board = board
        self.intrinsics = intrinsics
        self.clock: Any = None  # the simulated gantry's clock (None: real time)
        self.enabled = QCheckBox("Planar XY plan (both axes)")
        self.start_x, self.start_y = double_spin(-10000, 10000, 0.0, 3, " mm"), double_spin(-10000, 10000, 0.0, 3, " mm")
        self.stop_x, self.stop_y = double_spin(-10000, 10000, 40.0, 3, " mm"), double_spin(-10000, 10000, 20.0, 3, " mm")
        self.step_x, self.step_y = double_spin(0.001, 10000, 10.0, 3, " mm"), double_spin(0.001, 10000, 10.0, 3, " mm")
        self.pattern = QComboBox()
        for p in PATTERNS:
            self.pattern.addItem(p, p)
        self.iso_lines = QCheckBox("ISO 230-2 lines preset")
        self.iso_lines.setToolTip("Lines along X at 3 Y and along Y at 3 X; both ways, 5 runs")
        self.gantry = QComboBox()
        for label, key in GANTRY_PRESETS:
            self.gantry.addItem(label, key)
        self.demo_btn = QPushButton("Planar demo preset")
        self.demo_btn.setToolTip("A 5 x 3 grid at 10 mm, forward and backward, on the simulated gantry")
        self.distance_mm = double_spin(10.0, 100000.0, 600.0, 0, " mm")
        self.distance_mm.setToolTip("Camera-to-board distance for the prediction (the simulated gantry sets its own)")
        self.noise_px = double_spin(0.001, 10.0, NOISE_PX, 3, " px")
        self.noise_px.setToolTip("Corner noise the prediction assumes (rendered simulated images: about 0.02 px)")
        self.prediction = QLabel()
        self.prediction.setWordWrap(True)
        self.plot = pg.PlotWidget()
        self.plot.setBackground("w")
        self.plot.setMinimumHeight(220)
        self.plot.setAspectLocked(True)
        pi = self.plot.getPlotItem()
        pi.setLabel("bottom", "X target [mm]")
        pi.setLabel("left", "Y target [mm]")
        pi.showGrid(x=True, y=True, alpha=0.2)
        self.order_note = QLabel()

        def pair(a: QWidget, b: QWidget) -> QWidget:
            """X above Y: side by side they made the editor wider than a laptop's Capture dock (cut off)."""
            w = QWidget()
            grid = QGridLayout(w)
            grid.setContentsMargins(0, 0, 0, 0)
            grid.setVerticalSpacing(2)
            for r, (name, field) in enumerate((("X", a), ("Y", b))):
                grid.addWidget(QLabel(name), r, 0)
                grid.addWidget(field, r, 1)
            grid.setColumnStretch(1, 1)
            return w

        outer = QVBoxLayout(self)
        outer.setContentsMargins(6, 2, 6, 2)
        top = QGridLayout()  # one row while planar mode is off and the dock is wide; the button wraps under otherwise
        top.addWidget(self.enabled, 0, 0)
        top.addWidget(self.demo_btn, 1, 0, Qt.AlignmentFlag.AlignLeft)
        outer.addLayout(top)
        self.body = QWidget()
        outer.addWidget(self.body, 1)  # hidden until planar mode is on; the Capture dock scrolls, not a box of its own
        form = QFormLayout(self.body)
        form.setContentsMargins(0, 0, 0, 0)
        add_rows(form, [("Start", pair(self.start_x, self.start_y)),
                        ("Stop", pair(self.stop_x, self.stop_y)), ("Step", pair(self.step_x, self.step_y)),
                        ("Pattern", self.pattern), ("", self.iso_lines), ("Stage", self.gantry),
                        ("Camera distance", self.distance_mm), ("Corner noise", self.noise_px),
                        ("Rig prediction", self.prediction)])
        form.addRow(self.plot)
        form.addRow(self.order_note)

        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(250)
        self._timer.timeout.connect(self.refresh)
        for w in (self.start_x, self.start_y, self.stop_x, self.stop_y, self.step_x, self.step_y, self.distance_mm,
                  self.noise_px):
            w.valueChanged.connect(self._edited)
        for c in (self.pattern, self.gantry):
            c.currentIndexChanged.connect(self._edited)
        for c in (self.enabled, self.iso_lines):
            c.toggled.connect(self._edited)
        self.demo_btn.clicked.connect(self.apply_demo_preset)
        self._sync_enabled()

    # ------------------------------------------------------------------ the plan
    def active(self) -> bool:
        return self.enabled.isChecked()

    def gantry_preset(self) -> str:
        return str(self.gantry.currentData() or GANTRY_OFF)

    def plan(self, **shared: Any) -> Plan:
        """The planar plan of the fields, with the shared fields (``shared`` or the panel's); InputError if invalid."""
        fields = {k: v for k, v in {**self.shared(), **shared}.items() if k in SHARED_FIELDS}
        grid = Plan.xy(start_mm=(self.start_x.value(), self.start_y.value()),
                       stop_mm=(self.stop_x.value(), self.stop_y.value()),
                       step_mm=(self.step_x.value(), self.step_y.value()),
                       pattern=str(self.pattern.currentData()), **fields)
        if not self.iso_lines.isChecked():
            return grid
        return iso_lines_on_grid(grid, ISO_LEVELS, ISO_RUNS)

    def set_plan(self, plan: Plan) -> None:
        """Show ``plan`` (e.g. of a session being resumed); explicit target lists show their extent."""
        t = plan.targets()
        start = plan.start_mm if plan.targets_mm is None else (float(t[:, 0].min()), float(t[:, 1].min()))
        stop = plan.stop_mm if plan.targets_mm is None else (float(t[:, 0].max()), float(t[:, 1].max()))
        for (wx, wy), v in (((self.start_x, self.start_y), start), ((self.stop_x, self.stop_y), stop)):
            wx.setValue(v[0])
            wy.setValue(v[1])
        if plan.targets_mm is None:
            self.step_x.setValue(plan.step_mm[0])
            self.step_y.setValue(plan.step_mm[1])
        self.pattern.setCurrentIndex(max(0, self.pattern.findData(plan.pattern)))
        self.enabled.setChecked(True)
        self.refresh()

    def apply_demo_preset(self) -> None:
        """The planar demo: a 5 x 3 grid at 10 mm on the simulated small gantry (the quick `lps demo --planar`)."""
        self.enabled.setChecked(True)
        self.iso_lines.setChecked(False)
        self.gantry.setCurrentIndex(self.gantry.findData("small-planar"))
        for w, v in ((self.start_x, 0.0), (self.start_y, 0.0), (self.stop_x, 40.0), (self.stop_y, 20.0),
                     (self.step_x, 10.0), (self.step_y, 10.0)):
            w.setValue(v)
        self.pattern.setCurrentIndex(self.pattern.findData("serpentine"))
        self.set_shared({"directions": "both", "runs": 1, "settle_s": 0.1, "feed_mm_min": 3000.0})
        self.refresh()

    # ------------------------------------------------------------------ the simulated gantry
    def gantry_spec(self, plan: Plan) -> Any:
        """The simulated gantry's spec for ``plan`` (camera centred over it), or None when a real stage is used."""
        name = self.gantry_preset()
        if not name:
            return None
        from lps_gui.core.truth.simulate import PLANAR_PRESETS

        return PLANAR_PRESETS[name](plan=plan)

    def build_gantry(self, plan: Plan) -> tuple[Any, Any, Any] | None:
        """(spec, stage, camera) of the simulated gantry for ``plan``, the stage connected; None: no gantry chosen."""
        spec = self.gantry_spec(plan)
        if spec is None:
            return None
        from lps_gui.core.clock import RealClock
        from lps_gui.sim.rig import check_board_in_view, make_simulated_rig

        check_board_in_view(spec)
        stage, camera = make_simulated_rig(spec, clock=self.clock or RealClock())
        stage.connect()
        return spec, stage, camera

    def check_connected_rig(self, one_axis_simulation: bool) -> None:
        """InputError for a planar plan on the single-axis simulated rig (it has no Y axis to measure)."""
        if one_axis_simulation:
            raise InputError("planar plan: the simulated stage in the Stage panel has one axis; "
                             "choose Stage: Simulated gantry in the planar plan box, or connect an XY stage")

    def resume_rig(self, session: Any) -> tuple[Any, Any] | None:
        """For a planar session: show its plan; on the simulated gantry, rebuild it (stage connected).

        None: a single-axis session, or a planar one captured on real devices (the connected ones go on).
        """
        if not session.planar:
            return None
        self.set_plan(session.plan())
        truth = session.truth or {}
        if not (truth.get("simulated") and truth.get("axes") == ["X", "Y"]):
            return None
        from lps_gui.core.clock import RealClock
        from lps_gui.sim.session import reopen_simulated_rig

        stage, camera = reopen_simulated_rig(session, clock=self.clock or RealClock())
        stage.connect()
        return stage, camera

    # ------------------------------------------------------------------ drawing and prediction
    def _edited(self) -> None:
        self._sync_enabled()
        self._timer.start()
        self.changed.emit()

    def _sync_enabled(self) -> None:
        self.body.setVisible(self.active())
        grow = QSizePolicy.Policy.Expanding if self.active() else QSizePolicy.Policy.Maximum
        self.setSizePolicy(QSizePolicy.Policy.Preferred, grow)
        self.distance_mm.setEnabled(not self.gantry_preset())

    def refresh(self) -> None:
        """Redraw the grid and visiting order and recompute the rig prediction."""
        self._timer.stop()
        pi = self.plot.getPlotItem()
        pi.clear()
        try:
            plan = self.plan()
        except InputError as exc:
            self.order_note.setText(f"<span style='color:#b00020'>{exc}</span>")
            self.prediction.setText("")
            return
        path = visiting_path(plan)
        self.draw_path(pi, path)
        back = " then the backward pass in reverse order" if plan.directions == "both" else ""
        self.order_note.setText(f"{len(path)} targets per pass, visited 1, 2, 3, …{back}; "
                                f"{plan.runs} run(s), {plan.n_frames()} frames")
        self.prediction.setText(self.prediction_text(plan))

    def draw_path(self, pi: pg.PlotItem, path: np.ndarray) -> None:
        nodes = np.unique(path, axis=0)
        pi.addItem(pg.ScatterPlotItem(nodes[:, 0], nodes[:, 1], size=7, brush=pg.mkBrush("#777777"), pen=None))
        seg = np.diff(path, axis=0)
        if len(seg):
            # a move of one axis runs along a line of the plan; a move of both repositions between lines
            along = np.append((np.abs(seg) > 1e-9).sum(axis=1) <= 1, False)
            pi.addItem(pg.PlotDataItem(path[:, 0], path[:, 1], connect=along, pen=pg.mkPen("#1f5fa8", width=2)))
            pi.addItem(pg.PlotDataItem(path[:, 0], path[:, 1], connect=np.append(~along[:-1], False),
                                       pen=pg.mkPen("#999999", width=1, style=Qt.PenStyle.DashLine)))
        pi.addItem(pg.ScatterPlotItem([path[0, 0]], [path[0, 1]], size=12, symbol="s", brush=pg.mkBrush("#2a9d3c")))
        moving = np.flatnonzero(np.hypot(seg[:, 0], seg[:, 1]) > 0)
        for i in moving[:: max(1, int(np.ceil(moving.size / MAX_ARROWS)))]:
            mid = path[i] + 0.55 * seg[i]
            angle = float(np.degrees(np.arctan2(seg[i, 1], seg[i, 0])))
            # pyqtgraph's arrow points along its angle + 180 deg (tip first)
            pi.addItem(pg.ArrowItem(pos=(float(mid[0]), float(mid[1])), angle=180.0 - angle, headLen=12,
                                    tailLen=0, brush="#1f5fa8", pen=None))
        seen: set[tuple[float, float]] = set()
        for k, p in enumerate(path[:MAX_NUMBERS]):
            key = (float(p[0]), float(p[1]))
            if key in seen:
                continue  # the ISO lines revisit nodes: one number per node (its first visit)
            seen.add(key)
            label = pg.TextItem(str(k + 1), color="#a8326e", anchor=(-0.2, 1.1))
            label.setPos(*key)
            pi.addItem(label)
        pi.autoRange(padding=0.12)

    def prediction_text(self, plan: Plan) -> str:
        """The rig prediction as one or two lines (board in view, sigma to expect)."""
        if len(plan.targets()) > MAX_PREDICTED_TARGETS:
            return f"not computed for more than {MAX_PREDICTED_TARGETS} targets: run `lps plan-rig`"
        from lps_gui.core.planning.rig import predict_rig

        spec = self.gantry_spec(plan)
        if spec is not None:
            board, intr = spec.rig.board, spec.rig.intrinsics
            distance = float(round(abs(spec.rig.C0_board[2])))
        else:
            board, intr, distance = self.board(), self.intrinsics(), self.distance_mm.value()
            if intr is None:
                return "calibrate the camera (Intrinsics panel) to predict what the rig will see"
        try:
            r = predict_rig(board, intr, distance, plan, self.noise_px.value())
        except Exception as exc:  # a readout: say why, never stop the editor
            log.info("rig prediction failed", exc_info=True)
            return f"no prediction: {exc}"
        view = ("board in view at every target" if r.board_in_view
                else f"<span style='color:#b00020'>board leaves the view at {r.targets_losing_board} of "
                     f"{r.n_targets} targets</span>")
        sig = ("" if r.sigma_um_median is None
               else f"; expected position sigma {r.sigma_um_median:.2f} µm median, {r.sigma_um_max:.2f} µm max "
                    f"per coordinate at {self.noise_px.value():g} px corner noise")
        return f"{distance:.0f} mm from the board, board image {r.board_size_px[0]:.0f} x {r.board_size_px[1]:.0f} px: {view}{sig}"



def shared_from_panel(panel: Any) -> dict[str, Any]:
    """The capture panel's fields a planar plan shares with a line plan (directions, runs, overshoot...)."""
    return {"directions": str(panel.directions.currentData()), "runs": panel.runs.value(),
            "overshoot_mm": panel.overshoot_mm.value(), "settle_s": panel.settle_s.value(),
            "frames_per_stop": panel.frames_per_stop.value(), "feed_mm_min": panel.feed_mm_min.value()}


def planar_engine(session: Any, stage: Any, camera: Any) -> Any:
    """The capture engine of a session on the simulated gantry (it records the true pose per frame), else None."""
    truth = session.truth or {}
    if not (truth.get("simulated") and truth.get("axes") == ["X", "Y"] and hasattr(camera, "rig")):
        return None
    from lps_gui.sim.session import simulated_engine

    return simulated_engine(session, stage, camera)


def apply_shared_to_panel(panel: Any, fields: dict[str, Any]) -> None:
    """Set the capture panel's shared fields (e.g. the planar demo's directions, settle and feed)."""
    if "directions" in fields:
        panel.directions.setCurrentIndex(max(0, panel.directions.findData(fields["directions"])))
    for key in ("runs", "overshoot_mm", "settle_s", "frames_per_stop", "feed_mm_min"):
        if key in fields:
            getattr(panel, key).setValue(fields[key])
