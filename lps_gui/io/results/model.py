"""results.json read once into typed, frozen sections: what report, GUI and CLI read instead of dicts.

:func:`lps_gui.io.results.document.assemble_results` stays the one builder of the
document (a dict, written as it is); this module is its one reader.
:meth:`Results.from_dict` validates once, with a one-line :class:`InputError`
naming the file and the field (``figures.single_run.scale_ppm``), and gives:

* every section as a frozen dataclass whose fields are the keys readers use,
  typed (``float | None`` for a figure JSON may hold as null);
* an optional section that the document lacks as ``None``, a list as a tuple
  (empty when absent), never a dict to chain ``.get`` calls through;
* every key kept: a section's whole object in ``raw`` (``section.get(key)``
  for the keys of an open set, e.g. ISO 230-2 figures by name), and unknown
  top-level sections (from a later version) in ``Results.extra``;
  :meth:`Results.to_dict` gives the document back as read.

Adding a section: a :class:`~lps_gui.io.results.typed_json.Section` subclass in
:mod:`lps_gui.io.results.sections` with its fields (defaults for every
optional key) and one field on :class:`Results` (``name: Cls | None = None``);
the converter (:mod:`lps_gui.io.results.typed_json`) reads the types, nothing else is registered.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.errors import InputError
from lps_gui.io.results.sections import (
    AsmeB564,
    BoardRecord,
    EnvironmentRecord,
    ErrorMotions,
    Figures,
    Flag,
    Inputs,
    IntrinsicsRecord,
    Parameters,
    Position,
    Software,
    TargetRecord,
    TruthComparison,
    Uncertainty,
)
from lps_gui.io.results.typed_json import Section, finite_number, section_fields
from lps_gui.io.results.keys import DEVIATION_UM, MEASURED_MM, TARGET_MM

FIX = Section.fix
MAX_ABS_VALUE = 1e9  # mm or um: no stage measured by a camera is a kilometre long or off by one
LINE_KEYS = (TARGET_MM, MEASURED_MM, DEVIATION_UM)
PLANAR_KEYS = ("target_x_mm", "target_y_mm", "measured_x_mm", "measured_y_mm", "deviation_x_um", "deviation_y_um")


# ----------------------------------------------------------------------------- the document


@dataclass(frozen=True, kw_only=True)
class Results(Section):
    """A whole results.json (``"format": "lps-results/1"``); see docs/ARCHITECTURE.md for the schema."""

    format: str
    software: Software | None = None
    created: str | None = None
    method: str | None = None
    axes: tuple[str, ...] = ("X",)
    settings: Mapping[str, Any] = field(default_factory=dict)
    inputs: Inputs | None = None
    board: BoardRecord | None = None
    intrinsics: IntrinsicsRecord | None = None
    session_meta: Mapping[str, Any] = field(default_factory=dict)
    parameters: Parameters = field(default_factory=Parameters)
    positions: tuple[Position, ...]
    figures: Figures = field(default_factory=Figures)
    flags: tuple[Flag, ...] = ()
    timings_s: Mapping[str, Any] = field(default_factory=dict)
    truth_comparison: TruthComparison | None = None
    environment: EnvironmentRecord | None = None
    uncertainty: Uncertainty | None = None
    summary: tuple[Any, ...] = ()
    asme_b5_64: AsmeB564 | None = None
    targets: tuple[TargetRecord, ...] = ()  # SPEC 13: each target's pose and sigma (docs/targets.md)
    error_motions: ErrorMotions | None = None  # SPEC 14: per axis, six motions per stop (docs/error-motions.md)
    verdict: Mapping[str, Any] = field(default_factory=dict)  # decision rule, overall word, one row per check (issue 37)
    extra: Mapping[str, Any] = field(default_factory=dict, metadata={"not_read": True})  # sections not known here
    source: str = field(default="results", compare=False, metadata={"not_read": True})  # the file, for messages

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "", source: str = "results") -> Results:
        """The typed document; InputError naming ``source`` and the first field no estimate writes."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: not a JSON object; {FIX}")
        if not data.get("positions"):
            raise InputError(f"{source}: has no per-position table (no 'positions'); {FIX}")
        results = super().from_dict(data, where, source)
        known = {name for name, _, _ in section_fields(cls)}
        extra = {k: v for k, v in data.items() if k not in known}
        results = dataclasses.replace(results, extra=extra, source=source)
        _check_measured(results)
        return results

    @property
    def planar(self) -> bool:
        """Two axes (SPEC 10)."""
        return len(self.axes) == 2

    @property
    def stage_spec(self) -> Mapping[str, Any] | None:
        """The stage specification the session recorded, when the results carry it."""
        return self.extra.get("stage_spec") or self.session_meta.get("stage_spec") or None

    def sorted_positions(self) -> list[Position]:
        """The rows in capture-index order."""
        return sorted(self.positions, key=lambda r: r.index)

    def column(self, key: str, rows: Any = None) -> np.ndarray:
        """One numeric column of the positions (``rows``, default all in file order), NaN where absent, shape (K,)."""
        rows = self.positions if rows is None else rows
        return np.array([np.nan if (v := r.number(key)) is None else v for r in rows], dtype=float)

    def to_dict(self) -> dict[str, Any]:
        """The document as JSON data: the sections' objects in the order read, unknown sections kept.

        A section replaced (``dataclasses.replace(results, uncertainty=...)``) is written as its own object.
        """
        names = [name for name, _, _ in section_fields(type(self))]
        out: dict[str, Any] = {}
        for name in [*self.raw, *(n for n in names if n not in self.raw), *self.extra]:
            if name in out:
                continue
            if name in self.extra:
                out[name] = self.extra[name]
                continue
            value = getattr(self, name)
            if name in self.raw or isinstance(value, Section):  # a field's default is not written
                out[name] = _as_json(value, self.raw.get(name, value))
        return out


def _as_json(value: Any, read: Any) -> Any:
    """A field back as JSON data: a section as its object, sections in a tuple or mapping likewise, else as read."""
    if isinstance(value, Section):
        return value.raw
    if isinstance(value, tuple) and value and isinstance(value[0], Section):
        return [v.raw for v in value]
    if isinstance(value, Mapping) and value and all(isinstance(v, Section) for v in value.values()):
        return {k: v.raw for k, v in value.items()}
    return read


def _check_measured(results: Results) -> None:
    """The measured values of the views used are finite and of a size a stage has (a hand-edited file is not)."""
    keys = PLANAR_KEYS if results.planar else LINE_KEYS
    measured = 0
    for i, row in enumerate(results.positions):
        if not row.usable:
            continue
        for key in keys:
            value = row.raw.get(key)
            if value is None:  # not estimated (a method without that figure)
                continue
            if isinstance(value, str) or finite_number(value) is None or abs(float(value)) > MAX_ABS_VALUE:
                raise InputError(f"{results.source}: position {i} ({key}) is {value!r}, not a measured value; {FIX}")
            measured += key.startswith("measured")
    if not measured:
        raise InputError(f"{results.source}: no position holds a measured value; {FIX}")


def as_results(results: Results | Mapping[str, Any], source: str = "results") -> Results:
    """``results`` typed: a :class:`Results` as it is, a results dict (an estimate's, in memory) read once."""
    return results if isinstance(results, Results) else Results.from_dict(results, source=source)


def read_results(path: Path | str) -> Results:
    """results.json (a folder is taken to hold one) as :class:`Results`: the one reader of the file."""
    from lps_gui.io.results.document import read_results_document

    path, data = read_results_document(path)
    return Results.from_dict(data, source=str(path))
