"""What the capture panel asks for the report: specification (with presets), environment, identification.

The same fields as ``lps capture --spec/--board-temp/--operator ...`` (both
from :mod:`lps_gui.io.setup_fields`, both read into one
:class:`lps_gui.capture.setup.SessionSetup`); they go into session.json
(``stage_spec``, ``environment``, ``identification``) when the session is
created. A spin box at its minimum reads "not recorded" and is left out, so
nothing is invented.
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

from lps_gui.capture.setup import SessionSetup
from lps_gui.core.planning.presets import SPEC_PRESETS
from lps_gui.gui.widgets import add_rows, double_spin
from lps_gui.io.setup_fields import ENV_FIELDS, ID_FIELDS, SPEC_FIELDS

NOT_RECORDED = "not recorded"
NOT_SPECIFIED = "not specified"
PRESET_LABELS = {"paper": "paper's Table 1 (\u00b120, \u00b15, 38 \u00b5m)", "lead-screw-standard": "lead screw, standard",
                 "ball-screw-precision": "ball screw, precision"}


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
        self.env = {f.key: optional_spin(f.lo, f.hi, f.decimals, f.unit, NOT_RECORDED) for f in ENV_FIELDS}
        self.notes = QLineEdit()
        self.notes.setPlaceholderText("thermometer, where it was, anything a reader should know")
        self.ident = {f.key: QLineEdit() for f in ID_FIELDS}
        rows: list[tuple[str, QWidget]] = [("Specification", self.preset)]
        rows += [(label, self.spec[key]) for key, label in SPEC_FIELDS]
        rows += [(f.label, self.env[f.key]) for f in ENV_FIELDS]
        rows += [("Environment notes", self.notes)]
        rows += [(f.label, self.ident[f.key]) for f in ID_FIELDS]
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

    def setup(self, test: str | None = None) -> SessionSetup:
        """The operator's set-up of the form (``lps_gui.capture.setup``: `lps capture`'s switches build the same);
        a spin box at its minimum and an empty line are not given."""
        return SessionSetup(spec={k: spin_value(w) for k, w in self.spec.items()},
                            environment={k: spin_value(w) for k, w in self.env.items()}, env_notes=self.notes.text(),
                            identification={k: w.text() for k, w in self.ident.items()}, test=test,
                            where="capture panel: environment")

    def meta(self) -> dict[str, Any]:
        """session.json entries: only what was given, checked as session.json's are."""
        return self.setup().meta()

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
