"""JSON objects read into frozen, typed dataclasses: checked once, every key kept.

A :class:`Section` subclass declares the keys its readers use as fields with
type annotations (``float | None``, ``int``, ``str``, ``bool``, ``tuple[X, ...]``,
``Mapping[str, X]``, another ``Section``); :meth:`Section.from_dict` converts an
object by those types, one converter per type built once, and raises a
one-line :class:`InputError` naming the source and the field's path
(``figures.single_run.scale_ppm``) with the section's ``fix``. The object itself
stays in ``raw``: keys no field names are read with :meth:`Section.get` /
:meth:`Section.number` and nothing read is lost. The results.json sections are
in :mod:`lps_gui.io.results.sections`.
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
from typing import Any, Callable, ClassVar, Union

import numpy as np

from lps_gui.errors import InputError


def finite_number(v: Any) -> float | None:
    """A finite float, else None (bools, lists, non-numeric text and NaN are not figures)."""
    if type(v) is float:
        return v if math.isfinite(v) else None
    if isinstance(v, bool):
        return None
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


@dataclass(frozen=True, kw_only=True)
class Section:
    """A JSON object as typed fields; the object itself in ``raw`` (nothing read is lost)."""

    raw: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)
    fix: ClassVar[str] = "re-run `lps estimate` on the session"  # what the user does about a wrong field
    open_keys: ClassVar[bool] = False  # keys beyond the fields are an open set (figures by name, columns)

    @classmethod
    def of(cls, **values: Any) -> Any:
        """The section as a builder writes it: its fields by name, in the order results.json holds them, checked
        and converted by the same definition the readers use (a name no field has is a TypeError, unless the
        section's keys are an open set); a nested section is given as itself."""
        if not cls.open_keys:
            unknown = set(values) - {name for name, _, _ in section_fields(cls)}
            if unknown:
                raise TypeError(f"{cls.__name__} has no field {', '.join(sorted(unknown))}")
        return cls.from_dict({k: _as_json(v) for k, v in values.items()}, cls.__name__, "results builder")

    def to_dict(self) -> dict[str, Any]:
        """The JSON object, as built (:meth:`of`) or read: ``Section.from_dict(s.to_dict()) == s``."""
        return {k: _as_json(v) for k, v in self.raw.items()}

    def get(self, key: str, default: Any = None) -> Any:
        """A key of the object as written (for keys of an open set: figures by name, columns)."""
        return self.raw.get(key, default)

    def number(self, key: str) -> float | None:
        """``key``'s value as a finite float, None when absent, null or not a number."""
        return finite_number(self.raw.get(key))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "", source: str = "results") -> Any:
        """The section of a JSON object; InputError naming ``source`` and the field at ``where`` otherwise."""
        if not isinstance(data, Mapping):
            raise bad_value(source, where or cls.__name__, data, "a JSON object", cls.fix)
        values: dict[str, Any] = {"raw": data}
        for name, convert, required in section_fields(cls):
            value = data.get(name)
            if value is None:
                if required:
                    raise InputError(f"{source}: has no '{f'{where}.{name}' if where else name}'; {cls.fix}")
                continue
            values[name] = convert(value, f"{where}.{name}" if where else name, source, cls.fix)
        return cls(**values)


_PLAIN = frozenset((float, int, str, bool))


def _as_json(value: Any) -> Any:
    """A value as JSON data: a section as its object, lists and objects copied (the section keeps its own)."""
    if value is None or type(value) in _PLAIN:  # most values (a position's columns): no ABC checks
        return value
    if isinstance(value, Section):
        return value.to_dict()
    if isinstance(value, (list, tuple)):
        return [_as_json(v) for v in value]
    if isinstance(value, Mapping):
        return {k: _as_json(v) for k, v in value.items()}
    return value


@lru_cache(maxsize=None)
def section_fields(cls: type) -> tuple[tuple[str, Converter, bool], ...]:
    """(name, conversion, required) of a section's fields but ``raw``; types resolved once per class."""
    hints = typing.get_type_hints(cls)
    return tuple((f.name, _converter(hints[f.name]), f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING)
                 for f in dataclasses.fields(cls) if f.name != "raw" and not f.metadata.get("not_read"))


def bad_value(source: str, path: str, value: Any, what: str, fix: str) -> InputError:
    """"source: 'path' is value, not what; fix" (the value cut to 40 characters)."""
    text = repr(value)
    return InputError(f"{source}: '{path}' is {text if len(text) < 40 else text[:37] + '...'}, not {what}; {fix}")


Converter = Callable[[Any, str, str, str], Any]  # (value, path, source, fix) -> the value typed


@lru_cache(maxsize=None)
def _converter(kind: Any) -> Converter:
    """The conversion of one field type, built once per type (a long session has thousands of rows)."""
    origin = typing.get_origin(kind)
    if origin in (Union, types.UnionType):
        inner = _converter(next(k for k in typing.get_args(kind) if k is not type(None)))
        return lambda v, path, source, fix: None if v is None else inner(v, path, source, fix)
    if kind is Any:
        return lambda v, path, source, fix: v
    if kind in (float, int, bool, str):
        return _SCALARS[kind]
    if origin is tuple:
        item = typing.get_args(kind)[0]
        each = None if item is Any else _converter(item)

        def as_tuple(v: Any, path: str, source: str, fix: str) -> tuple[Any, ...]:
            if not isinstance(v, (list, tuple)):
                raise bad_value(source, path, v, "a JSON list", fix)
            return tuple(v) if each is None else tuple(each(x, f"{path}[{i}]", source, fix) for i, x in enumerate(v))
        return as_tuple
    if origin is Mapping:
        item = typing.get_args(kind)[1]
        each = None if item is Any else _converter(item)

        def as_mapping(v: Any, path: str, source: str, fix: str) -> Mapping[str, Any]:
            if not isinstance(v, Mapping):
                raise bad_value(source, path, v, "a JSON object", fix)
            return v if each is None else {k: each(x, f"{path}.{k}", source, fix) for k, x in v.items()}
        return as_mapping
    if isinstance(kind, type) and issubclass(kind, Section):
        return lambda v, path, source, fix: kind.from_dict(v, path, source)
    raise TypeError(f"results_model: no conversion for {kind!r}")  # a field declared with a new type


def _real(v: Any) -> bool:
    return type(v) is float or type(v) is int or (not isinstance(v, bool) and isinstance(v, numbers.Real))


def _as_float(v: Any, path: str, source: str, fix: str) -> float:
    if not _real(v):
        raise bad_value(source, path, v, "a number", fix)
    return float(v)


def _as_int(v: Any, path: str, source: str, fix: str) -> int:
    if type(v) is int:
        return v
    if not _real(v) or float(v) != int(v):
        raise bad_value(source, path, v, "a whole number", fix)
    return int(v)


def _as_bool(v: Any, path: str, source: str, fix: str) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise bad_value(source, path, v, "true or false", fix)
    return bool(v)


def _as_str(v: Any, path: str, source: str, fix: str) -> str:
    if not isinstance(v, str):
        raise bad_value(source, path, v, "a text", fix)
    return v


_SCALARS: dict[type, Converter] = {float: _as_float, int: _as_int, bool: _as_bool, str: _as_str}
