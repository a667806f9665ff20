"""The operator's session set-up: what a new session records besides its plan and images, validated once.

`lps capture` (switches) and the GUI's capture panel (a form) are two faces of :class:`SessionSetup`:
each builds one from what the operator gave, and :func:`apply_setup` writes its :meth:`~SessionSetup.meta`
into session.json, so the same inputs give the same session.json (``stage_spec``, ``environment``,
``asme_test``, ``identification``). The fields are :mod:`lps_gui.io.setup_fields`; the plan of an
ASME B5.64 test is :func:`asme_plan_fields`, the presets of :mod:`lps_gui.core.planning.presets`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from lps_gui.core.metrology.environment import Environment
from lps_gui.core.planning.presets import (
    asme_test_record,
    min_step_plan_fields,
    parse_spec,
    settling_plan_fields,
)
from lps_gui.errors import InputError


@dataclass(frozen=True)
class SessionSetup:
    """What the operator gave for the report and the test; empty fields are left out of session.json."""

    spec: str | Mapping[str, float] | None = None  # a --spec text (preset or accuracy=UM,...) or the form's limits
    environment: Mapping[str, float] = field(default_factory=dict)  # io.setup_fields.ENV_FIELDS key -> value given
    env_notes: str = ""
    identification: Mapping[str, str] = field(default_factory=dict)  # io.setup_fields.ID_FIELDS key -> text
    test: str | None = None  # the ASME B5.64 test the plan is: "min-step" or "settling"
    test_step_um: float | None = None  # min-step: the commanded step (the preset's when None)
    test_band_um: float | None = None  # settling: the band around rest (the preset's when None)
    where: str = "session set-up"  # how the face names its environment entries in an error

    def stage_spec(self) -> dict[str, float] | None:
        """session.json ``stage_spec``: a text parsed as `--spec` reads it, the form's limits checked alike."""
        if not self.spec:
            return None
        if isinstance(self.spec, str):
            return parse_spec(self.spec)
        out = {}
        for key, value in self.spec.items():
            if value is None:
                continue
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InputError(f"{self.where}: specification {key} = {value!r}; a limit must be a positive number")
            out[key] = float(value)
        return out or None

    def test_record(self) -> dict[str, Any] | None:
        """session.json ``asme_test`` (None without a test)."""
        if not self.test:
            return None
        if self.test == "min-step":
            return asme_test_record("min-step", step_um=self.test_step_um)
        return asme_test_record(self.test, band_um=self.test_band_um)

    def meta(self) -> dict[str, Any]:
        """session.json entries, only those given; one-line ``InputError`` naming the entry that is wrong."""
        out: dict[str, Any] = {}
        spec = self.stage_spec()
        if spec:
            out["stage_spec"] = spec
        env: dict[str, Any] = {k: v for k, v in self.environment.items() if v is not None}
        if self.env_notes.strip():
            env["notes"] = self.env_notes.strip()
        if env:
            out["environment"] = Environment.from_dict(env, self.where).to_dict()
        test = self.test_record()
        if test:
            out["asme_test"] = test
        ident = {k: str(v).strip() for k, v in self.identification.items() if v is not None and str(v).strip()}
        if ident:
            out["identification"] = ident
        return out


def device_records(stage: Any, camera: Any, stage_source: str | None = None, camera_source: str | None = None,
                   **stage_meta: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """session.json ``stage`` and ``camera`` of the devices a session runs on: the stage's description with the
    capabilities its driver declared (SPEC 16), the camera's properties, and the source each was opened from
    (``spec``: what `lps capture --resume` reopens) when the face knows it."""
    from lps_gui.hardware.capabilities import session_stage

    stage_record = {**session_stage(stage), **stage_meta, **({"spec": stage_source} if stage_source else {})}
    return stage_record, {**camera.properties(), **({"spec": camera_source} if camera_source else {})}


def apply_setup(session: Any, extra: dict[str, Any]) -> None:
    """Merge :meth:`SessionSetup.meta` into session.json (environment and identification key by key) and save it:
    a new session gets the entries, a resumed one keeps what it had where nothing new was given."""
    if not extra:
        return
    for key, value in extra.items():
        if isinstance(value, dict) and key != "stage_spec":
            session.meta[key] = {**(session.meta.get(key) or {}), **value}
        else:
            session.meta[key] = value
    session.save_meta()


def asme_plan_fields(test: str, start_mm: float, stop_mm: float, step_um: float | None = None,
                     steps: int | None = None) -> dict[str, Any]:
    """Plan fields of an ASME B5.64 test over [start, stop] (the presets; a one-line error when it does not fit)."""
    if test == "min-step":
        kw = {k: v for k, v in (("step_um", step_um), ("steps", steps)) if v is not None}
        return min_step_plan_fields(float(start_mm), float(stop_mm), **kw)
    if test == "settling":
        return settling_plan_fields(float(start_mm), float(stop_mm))
    asme_test_record(test)  # names the tests there are
    return {}
