"""What the capture panel asks for the report: specification (with presets), environment, identification.

The same fields as ``lps capture --spec/--board-temp/--operator ...``; they go
into session.json (``stage_spec``, ``environment``, ``identification``) when
the session is created. A spin box at its minimum reads "not recorded" and
is left out, so nothing is invented.
"""
from __future__ import annotations

from typing import Any

from PySide6.QtCore import QSettings, Qt, Signal
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QLabel,
    QLineEdit,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from lps_gui.core.metrology.environment import Environment
from lps_gui.core.planning.presets import SPEC_PRESETS
from lps_gui.gui.widgets import add_rows, double_spin

NOT_RECORDED = "not recorded"
NOT_SPECIFIED = "not specified"
PRESET_LABELS = {"paper": "paper's Table 1 (\u00b120, \u00b15, 38 \u00b5m)", "lead-screw-standard": "lead screw, standard",
                 "ball-screw-precision": "ball screw, precision"}
# (environment key, label, lowest real value, highest, decimals, unit)
ENV_FIELDS = (("board_temperature_c", "Board temperature", -50.0, 100.0, 2, " \u00b0C"),
              ("board_cte_ppm_per_k", "Board expansion", 0.0, 100.0, 2, " ppm/K"),
              ("square_mm_uncertainty_um", "Square size u", 0.0, 100.0, 3, " \u00b5m"),
              ("stage_temperature_c", "Stage temperature", -50.0, 100.0, 2, " \u00b0C"),
              ("stage_cte_ppm_per_k", "Stage expansion", 0.0, 100.0, 2, " ppm/K"))
ID_FIELDS = (("operator", "Operator"), ("customer", "Customer"), ("stage_model", "Stage model"),
             ("stage_serial", "Stage serial"),  # then the signing block's (lps_gui.report.pages.signing.SIGNING_FIELDS)
             ("lab", "Laboratory"), ("certificate_number", "Certificate no."), ("board_id", "Board id"),
             ("board_certificate", "Board certificate"), ("thermometer", "Thermometer"),
             ("thermometer_certificate", "Thermometer cert."), ("camera_serial", "Camera serial"),
             ("camera_certificate", "Camera certificate"), ("approved_by", "Approved by"))
SPEC_FIELDS = (("accuracy_um", "Accuracy \u00b1"), ("repeatability_um", "Repeatability \u00b1"),
               ("straightness_um", "Straight-line accuracy"))


def optional_spin(lo: float, hi: float, decimals: int, suffix: str, empty: str) -> QDoubleSpinBox:
    """A spin box whose lowest value (one step below ``lo``) means "not given"."""
    step = 10.0 ** -decimals
    s = double_spin(lo - step, hi, lo - step, decimals, suffix)
    s.setSpecialValueText(empty)
    return s


def spin_value(s: QDoubleSpinBox) -> float | None:
    return None if s.value() <= s.minimum() else float(s.value())


class ReportSetupBox(QGroupBox):
    """Specification, environment and identification of the next session; folded to one line until opened."""

    changed = Signal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__("For the report", parent)
        self.toggle = QToolButton()
        self.toggle.setCheckable(True)
        self.toggle.setText("Specification, environment, identification \u25b8")
        self.toggle.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        self.brief = QLabel()
        self.brief.setWordWrap(True)
        self.fields = QWidget()
        outer = QVBoxLayout(self)
        outer.setContentsMargins(6, 6, 6, 6)
        outer.addWidget(self.toggle)
        outer.addWidget(self.brief)
        outer.addWidget(self.fields)
        self.fields.setVisible(False)  # folded: the panel keeps its height on small screens
        self.toggle.toggled.connect(self.unfold)
        self.preset = QComboBox()
        self.preset.addItem("custom", "")
        for key in SPEC_PRESETS:
            self.preset.addItem(PRESET_LABELS.get(key, key), key)
        self.spec = {key: optional_spin(0.001, 10000.0, 3, " \u00b5m", NOT_SPECIFIED) for key, _ in SPEC_FIELDS}
        self.env = {key: optional_spin(lo, hi, dec, unit, NOT_RECORDED) for key, _, lo, hi, dec, unit in ENV_FIELDS}
        self.notes = QLineEdit()
        self.notes.setPlaceholderText("thermometer, where it was, anything a reader should know")
        self.ident = {key: QLineEdit() for key, _ in ID_FIELDS}
        rows: list[tuple[str, QWidget]] = [("Specification", self.preset)]
        rows += [(label, self.spec[key]) for key, label in SPEC_FIELDS]
        rows += [(label, self.env[key]) for key, label, *_ in ENV_FIELDS]
        rows += [("Environment notes", self.notes)]
        rows += [(label, self.ident[key]) for key, label in ID_FIELDS]
        form = QFormLayout(self.fields)
        form.setContentsMargins(0, 0, 0, 0)
        add_rows(form, rows)
        self.preset.currentIndexChanged.connect(self._apply_preset)
        for w in (*self.spec.values(), *self.env.values()):
            w.valueChanged.connect(self.changed)
        for key, w in self.spec.items():
            w.valueChanged.connect(lambda _v, key=key: self._edited(key))
        for w in (self.notes, *self.ident.values()):
            w.textChanged.connect(self.changed)
        self.changed.connect(self._update_brief)
        self._update_brief()

    def unfold(self, on: bool) -> None:
        self.fields.setVisible(on)
        self.toggle.setText("Specification, environment, identification " + ("\u25be" if on else "\u25b8"))

    def _update_brief(self) -> None:
        """One line of what the next session will record."""
        try:
            meta = self.meta()
        except Exception as exc:  # an impossible value: say so where it is seen
            self.brief.setText(f"<span style='color:#b00020'>{exc}</span>")
            return
        spec = meta.get("stage_spec") or {}
        preset = self.preset.currentData()
        parts = [PRESET_LABELS.get(preset, preset) if preset else
                 (", ".join(f"{k.removesuffix('_um')} {v:g} \u00b5m" for k, v in spec.items()) or "no specification")]
        env = meta.get("environment") or {}
        parts.append(f"board {env['board_temperature_c']:g} \u00b0C" if "board_temperature_c" in env
                     else "board temperature not recorded")
        ident = meta.get("identification") or {}
        if ident.get("operator"):
            parts.append(f"operator {ident['operator']}")
        self.brief.setText("; ".join(parts))
    def _apply_preset(self) -> None:
        key = self.preset.currentData()
        if not key:
            return
        for name, w in self.spec.items():
            w.blockSignals(True)
            w.setValue(SPEC_PRESETS[key].get(name, w.minimum()))
            w.blockSignals(False)
        self.changed.emit()

    def _edited(self, key: str) -> None:
        preset = self.preset.currentData()
        if preset and spin_value(self.spec[key]) != SPEC_PRESETS[preset].get(key):
            self.preset.blockSignals(True)
            self.preset.setCurrentIndex(0)  # edited by hand: no longer the preset
            self.preset.blockSignals(False)

    def select_preset(self, key: str) -> None:
        self.preset.setCurrentIndex(max(0, self.preset.findData(key)))
        self._update_brief()

    def meta(self) -> dict[str, Any]:
        """session.json entries: only what was given; the environment is checked like session.json's."""
        out: dict[str, Any] = {}
        spec = {k: v for k, w in self.spec.items() if (v := spin_value(w)) is not None}
        if spec:
            out["stage_spec"] = spec
        env: dict[str, Any] = {k: v for k, w in self.env.items() if (v := spin_value(w)) is not None}
        if self.notes.text().strip():
            env["notes"] = self.notes.text().strip()
        if env:
            out["environment"] = Environment.from_dict(env, "capture panel: environment").to_dict()
        ident = {k: w.text().strip() for k, w in self.ident.items() if w.text().strip()}
        if ident:
            out["identification"] = ident
        return out

    # ------------------------------------------------------------------ settings
    def save(self, s: QSettings) -> None:
        s.setValue("report/preset", self.preset.currentData() or "")
        for k, w in {**self.spec, **self.env}.items():
            s.setValue(f"report/{k}", w.value())
        for k, w in self.ident.items():
            s.setValue(f"report/{k}", w.text())
        s.setValue("report/notes", self.notes.text())

    def restore(self, s: QSettings) -> None:
        for k, w in {**self.spec, **self.env}.items():
            v = s.value(f"report/{k}")
            if v is not None:
                try:
                    w.setValue(float(v))
                except (TypeError, ValueError):
                    pass
        for k, w in self.ident.items():
            w.setText(str(s.value(f"report/{k}") or ""))
        self.notes.setText(str(s.value("report/notes") or ""))
        preset = str(s.value("report/preset") or "")
        if preset:
            self.preset.blockSignals(True)
            self.select_preset(preset)
            self.preset.blockSignals(False)
