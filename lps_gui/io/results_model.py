"""results.json read once into typed, frozen sections: what report, GUI and CLI read instead of dicts.

:func:`lps_gui.io.results_file.assemble_results` stays the one builder of the
document (a dict, written as it is); this module is its one reader.
:meth:`Results.from_dict` validates once, with a one-line :class:`InputError`
naming the file and the field (``figures.single_run.scale_ppm``), and gives:

* every section as a frozen dataclass whose fields are the keys readers use,
  typed (``float | None`` for a figure JSON may hold as null);
* an optional section that the document lacks as ``None``, a list as a tuple
  (empty when absent), never a dict to chain ``.get`` calls through;
* every key kept: a section's whole object in ``raw`` (``section.get(key)``
  for the keys of an open set, e.g. ISO 230-2 figures by name), and unknown
  top-level sections (``targets``, error motions, ...) in ``Results.extra``;
  :meth:`Results.to_dict` gives the document back as read.

Adding a section: a :class:`Section` subclass with its fields (defaults for
every optional key) and one field on :class:`Results` (``name: Cls | None =
None``); the converter reads the types, nothing else is registered.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Union

import numpy as np

from lps_gui.errors import InputError

FIX = "re-run `lps estimate` on the session"
MAX_ABS_VALUE = 1e9  # mm or um: no stage measured by a camera is a kilometre long or off by one
LINE_KEYS = ("target_mm", "measured_mm", "deviation_um")
PLANAR_KEYS = ("target_x_mm", "target_y_mm", "measured_x_mm", "measured_y_mm", "deviation_x_um", "deviation_y_um")


def _number(value: Any) -> float | None:
    """A finite float, else None (null, strings, bools and NaN are no figure)."""
    if type(value) is float:
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    f = float(value)
    return f if math.isfinite(f) else None


# ----------------------------------------------------------------------------- the converter


@dataclass(frozen=True, kw_only=True)
class Section:
    """A JSON object as typed fields; the object itself in ``raw`` (nothing read is lost)."""

    raw: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def get(self, key: str, default: Any = None) -> Any:
        """A key of the object as written (for keys of an open set: figures by name, columns)."""
        return self.raw.get(key, default)

    def number(self, key: str) -> float | None:
        """``key``'s value as a finite float, None when absent, null or not a number."""
        return _number(self.raw.get(key))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "", source: str = "results") -> Any:
        """The section of a JSON object; InputError naming ``source`` and the field at ``where`` otherwise."""
        if not isinstance(data, Mapping):
            raise _bad(source, where or cls.__name__, data, "a JSON object")
        values: dict[str, Any] = {"raw": data}
        for name, convert, required in _fields(cls):
            value = data.get(name)
            if value is None:
                if required:
                    raise InputError(f"{source}: has no '{f'{where}.{name}' if where else name}'; {FIX}")
                continue
            values[name] = convert(value, f"{where}.{name}" if where else name, source)
        return cls(**values)


@lru_cache(maxsize=None)
def _fields(cls: type) -> tuple[tuple[str, Converter, bool], ...]:
    """(name, conversion, required) of a section's fields but ``raw``; types resolved once per class."""
    hints = typing.get_type_hints(cls)
    return tuple((f.name, _converter(hints[f.name]), f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING)
                 for f in dataclasses.fields(cls) if f.name != "raw" and not f.metadata.get("not_read"))


def _bad(source: str, path: str, value: Any, what: str) -> InputError:
    text = repr(value)
    return InputError(f"{source}: '{path}' is {text if len(text) < 40 else text[:37] + '...'}, not {what}; {FIX}")


Converter = Callable[[Any, str, str], Any]


@lru_cache(maxsize=None)
def _converter(kind: Any) -> Converter:
    """The conversion of one field type, built once per type (a long session has thousands of rows)."""
    origin = typing.get_origin(kind)
    if origin in (Union, types.UnionType):
        inner = _converter(next(k for k in typing.get_args(kind) if k is not type(None)))
        return lambda v, path, source: None if v is None else inner(v, path, source)
    if kind is Any:
        return lambda v, path, source: v
    if kind in (float, int, bool, str):
        return _SCALARS[kind]
    if origin is tuple:
        item = typing.get_args(kind)[0]
        each = None if item is Any else _converter(item)

        def as_tuple(v: Any, path: str, source: str) -> tuple[Any, ...]:
            if not isinstance(v, (list, tuple)):
                raise _bad(source, path, v, "a JSON list")
            return tuple(v) if each is None else tuple(each(x, f"{path}[{i}]", source) for i, x in enumerate(v))
        return as_tuple
    if origin is Mapping:
        item = typing.get_args(kind)[1]
        each = None if item is Any else _converter(item)

        def as_mapping(v: Any, path: str, source: str) -> Mapping[str, Any]:
            if not isinstance(v, Mapping):
                raise _bad(source, path, v, "a JSON object")
            return v if each is None else {k: each(x, f"{path}.{k}", source) for k, x in v.items()}
        return as_mapping
    if isinstance(kind, type) and issubclass(kind, Section):
        return kind.from_dict
    raise TypeError(f"results_model: no conversion for {kind!r}")  # a field declared with a new type


def _real(v: Any) -> bool:
    return type(v) is float or type(v) is int or (not isinstance(v, bool) and isinstance(v, numbers.Real))


def _as_float(v: Any, path: str, source: str) -> float:
    if not _real(v):
        raise _bad(source, path, v, "a number")
    return float(v)


def _as_int(v: Any, path: str, source: str) -> int:
    if type(v) is int:
        return v
    if not _real(v) or float(v) != int(v):
        raise _bad(source, path, v, "a whole number")
    return int(v)


def _as_bool(v: Any, path: str, source: str) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise _bad(source, path, v, "true or false")
    return bool(v)


def _as_str(v: Any, path: str, source: str) -> str:
    if not isinstance(v, str):
        raise _bad(source, path, v, "a text")
    return v


_SCALARS: dict[type, Converter] = {float: _as_float, int: _as_int, bool: _as_bool, str: _as_str}


# ----------------------------------------------------------------------------- sections


@dataclass(frozen=True, kw_only=True)
class Software(Section):
    name: str | None = None
    version: str | None = None


@dataclass(frozen=True, kw_only=True)
class Inputs(Section):
    """What the estimate read: the session folder, the hashes of its files, where the intrinsics came from."""

    session: str | None = None
    intrinsics_source: str | None = None
    sha256: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class BoardRecord(Section):
    """The board as the estimate used it (``square_mm`` nominal at 20 C; ``environment.square_mm_used``)."""

    type: str | None = None
    inner_corners: tuple[int, ...] = ()
    square_mm: float | None = None


@dataclass(frozen=True, kw_only=True)
class IntrinsicsRecord(Section):
    """The camera intrinsics the estimate used, with their 1-sigma (``std``, by name) when known."""

    image_size: tuple[int, ...] = ()
    camera_matrix: tuple[tuple[float, ...], ...] = ()
    dist: tuple[float, ...] = ()
    std: Mapping[str, float | None] = field(default_factory=dict)
    rms_px: float | None = None
    n_views: int | None = None

    @property
    def K(self) -> np.ndarray:
        """The camera matrix, shape (3, 3); the identity when the record has none."""
        return np.asarray(self.camera_matrix, dtype=float) if self.camera_matrix else np.eye(3)


@dataclass(frozen=True, kw_only=True)
class Parameters(Section):
    """The fit: its statistics (the stage line's vectors stay in ``raw``: R_cam_board, l0_cam_mm, n_cam, ...)."""

    sigma_px: float | None = None
    rms_px: float | None = None
    n_views: int | None = None
    n_used: int | None = None
    n_outliers: int | None = None
    n_observations: int | None = None
    dof: int | None = None
    iterations: int | None = None
    converged: bool | None = None
    reference_index: int | None = None


@dataclass(frozen=True, kw_only=True)
class Position(Section):
    """One capture's row: identity and flags typed; measured columns by name (:meth:`Section.number`)."""

    index: int
    run: int | None = None
    direction: str = "+"
    outlier: bool = False
    outlier_reason: str | None = None
    used: bool | None = None
    file: str | None = None

    @property
    def usable(self) -> bool:
        """The estimate used this view (``used``; older files: not an outlier)."""
        return self.used if self.used is not None else not self.outlier


@dataclass(frozen=True, kw_only=True)
class Flag(Section):
    index: int | None = None
    kind: str | None = None
    message: str | None = None


@dataclass(frozen=True, kw_only=True)
class Spectrum(Section):
    period_mm: tuple[float | None, ...] = ()
    amplitude_um: tuple[float | None, ...] = ()
    method: str | None = None


@dataclass(frozen=True, kw_only=True)
class SingleRun(Section):
    """``figures.single_run``: the figures of all captures as one run (SPEC 5)."""

    mean_step_mm: float | None = None
    step_std_um: float | None = None
    max_abs_deviation_um: float | None = None
    deviation_span_um: float | None = None
    scale_ppm: float | None = None
    scale_sigma_ppm: float | None = None
    scale_sigma_total_ppm: float | None = None
    periodic_amplitude_um: float | None = None
    periodic_period_mm: float | None = None
    spectrum: Spectrum | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class Iso230(Section):
    """``figures.iso230_2``: E/M/B/R/A by name (``get("A_um")``; an open set), per-target table, notes."""

    n_targets: int | None = None
    n_runs_up: int | None = None
    n_runs_down: int | None = None
    per_target: Mapping[str, Any] | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class SpanResolution(Section):
    """A peak-to-valley over the targets and what noise alone would span (core/resolution.py)."""

    span_um: float | None = None
    sigma_um: float | None = None
    noise_span_um: float | None = None
    n_targets: int | None = None
    resolved: bool | None = None


@dataclass(frozen=True, kw_only=True)
class Straightness(Section):
    basis: str | None = None
    v1: SpanResolution | None = None
    v2: SpanResolution | None = None


@dataclass(frozen=True, kw_only=True)
class ImageRotation(Section):
    span_urad: float | None = None
    sigma_urad: float | None = None
    noise_span_urad: float | None = None
    n_targets: int | None = None
    resolved: bool | None = None


@dataclass(frozen=True, kw_only=True)
class AngleResolution(Section):
    max_abs_urad: float | None = None
    noise_max_abs_urad: float | None = None
    resolved: bool | None = None


@dataclass(frozen=True, kw_only=True)
class PlanarNode(Section):
    """One grid node of the planar error map: mean error vector (um) at its target (mm)."""

    target_mm: tuple[float, ...] = ()
    n: int | None = None
    error_um: tuple[float | None, ...] | None = None
    sigma_um: Any = None
    truth_error_um: tuple[float | None, ...] | None = None


@dataclass(frozen=True, kw_only=True)
class Figures(Section):
    """``figures``: single-run, per-run, ISO 230-2, straightness and angle figures; ``planar`` for SPEC 10."""

    single_run: SingleRun | None = None
    per_run: tuple[Any, ...] = ()
    iso230_2: Iso230 | None = None
    straightness_um_max: float | None = None
    straightness_span_um: tuple[float | None, ...] = ()
    straightness_sigma_um: float | None = None
    straightness: Straightness | None = None
    image_rotation: ImageRotation | None = None
    angles_resolution: Mapping[str, AngleResolution] = field(default_factory=dict)
    angles_span_urad: Mapping[str, float | None] = field(default_factory=dict)
    planar: PlanarFigures | None = None


@dataclass(frozen=True, kw_only=True)
class PlanarAxis(Section):
    """``figures.planar.per_axis[X|Y]``: the worst line's straightness and ISO 230-2 block of one axis."""

    lines: int | None = None
    straightness_um_max: float | None = None
    straightness_sigma_um: float | None = None
    straightness: SpanResolution | None = None
    out_of_plane: SpanResolution | None = None
    iso230_2: Figures | None = None  # that axis's figures shaped like a line session's ``figures``


@dataclass(frozen=True, kw_only=True)
class PlanarFigures(Section):
    """``figures.planar`` (SPEC 10): squareness, per-axis scales, the axes' figures, the grid's nodes."""

    squareness_urad: float | None = None
    squareness_sigma_urad: float | None = None
    squareness_um_per_m: float | None = None
    scale_x_ppm: float | None = None
    scale_x_sigma_ppm: float | None = None
    scale_y_ppm: float | None = None
    scale_y_sigma_ppm: float | None = None
    per_axis: Mapping[str, PlanarAxis] = field(default_factory=dict)
    lines: tuple[Any, ...] = ()
    nodes: tuple[PlanarNode, ...] = ()
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class TruthComparison(Section):
    """``truth_comparison`` (simulated sessions): the estimate against the simulator's truth.

    An open set of figures (:meth:`numbers`); those that readers name are typed.
    """

    position_rms_error_um: float | None = None
    position_max_abs_error_um: float | None = None
    mean_sigma_um: float | None = None
    median_sigma_um: float | None = None
    z_mean_square: float | None = None
    injected_outliers: tuple[Any, ...] = ()
    flagged_outliers: tuple[Any, ...] = ()
    board_plane_rms_error_um: float | None = None
    board_plane_z_mean_square: float | None = None
    abbe_rms_um: float | None = None
    reference: str | None = None  # planar: the frame the errors are taken in
    per_coordinate_rms_error_um: tuple[float | None, ...] | None = None
    squareness_urad: float | None = None
    squareness_error_urad: float | None = None
    squareness_z: float | None = None
    scale_x_error_ppm: float | None = None
    scale_y_error_ppm: float | None = None
    out_of_plane_rms_error_um: float | None = None
    out_of_plane_z_mean_square: float | None = None

    def numbers(self) -> list[tuple[str, float]]:
        """(key, value) of every finite numeric figure, in the document's order."""
        return [(k, v) for k, v in ((k, _number(v)) for k, v in self.raw.items()) if v is not None]


@dataclass(frozen=True, kw_only=True)
class EnvironmentRecord(Section):
    """``environment``: the temperatures and coefficients recorded, and the thermal correction applied."""

    board_temperature_c: float | None = None
    board_cte_ppm_per_k: float | None = None
    square_mm_uncertainty_um: float | None = None
    stage_temperature_c: float | None = None
    stage_cte_ppm_per_k: float | None = None
    temperature_uncertainty_k: float | None = None
    notes: str | None = None
    reference_temperature_c: float | None = None
    board_scale_correction_ppm: float | None = None
    square_mm_nominal: float | None = None
    square_mm_used: float | None = None


@dataclass(frozen=True, kw_only=True)
class BudgetRow(Section):
    """One source of the GUM budget (core/uncertainty_budget.py)."""

    source: str
    type: str | None = None
    value: float | None = None
    unit: str | None = None
    sensitivity: float | None = None
    contribution_um: float | None = None
    note: str | None = None


@dataclass(frozen=True, kw_only=True)
class Uncertainty(Section):
    """``uncertainty``: the budget, U (k = 2) of every figure; a planar session's in ``per_axis``."""

    budget: tuple[BudgetRow, ...] = ()
    combined_standard_um: float | None = None
    coverage_factor: float | None = None
    expanded_k2_um: float | None = None
    noise_standard_um: float | None = None
    not_in_u: tuple[str, ...] = ()
    applies_to: str | None = None
    travel_mm: float | None = None
    figures_k2: Mapping[str, float | None] = field(default_factory=dict)
    per_axis: Mapping[str, Uncertainty] = field(default_factory=dict)

    def u_k2(self, key: str) -> float | None:
        """U (k = 2) of the figure ``key`` of ``figures_k2``, None when not assessed."""
        return _number(self.figures_k2.get(key))


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
        known = {name for name, _, _ in _fields(cls)}
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
        names = [name for name, _, _ in _fields(type(self))]
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
            if _number(value) is None or abs(float(value)) > MAX_ABS_VALUE:
                raise InputError(f"{results.source}: position {i} ({key}) is {value!r}, not a measured value; {FIX}")
            measured += key.startswith("measured")
    if not measured:
        raise InputError(f"{results.source}: no position holds a measured value; {FIX}")


def as_results(results: Results | Mapping[str, Any], source: str = "results") -> Results:
    """``results`` typed: a :class:`Results` as it is, a results dict (an estimate's, in memory) read once."""
    return results if isinstance(results, Results) else Results.from_dict(results, source=source)


def read_results(path: Path | str) -> Results:
    """results.json (a folder is taken to hold one) as :class:`Results`: the one reader of the file."""
    from lps_gui.io.results_file import read_results_document

    path, data = read_results_document(path)
    return Results.from_dict(data, source=str(path))
