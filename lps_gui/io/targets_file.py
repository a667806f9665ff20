"""session.json ``targets`` (SPEC 13): read and write the list of mounted ChArUco targets."""
from __future__ import annotations

import math
from typing import Any

from lps_gui.core.geometry.targets import Target, check_targets
from lps_gui.errors import InputError
from lps_gui.io.board_file import board_from_dict, board_to_dict


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _whole(value: Any) -> bool:
    return _finite(value) and float(value) == int(value)


FIELDS = ("id", "type", "inner_corners", "square_mm", "marker_mm", "dictionary", "first_marker",
          "square_mm_uncertainty_um", "scale_ppm")


def _optional_number(d: dict[str, Any], key: str, source: str) -> float | None:
    value = d.get(key)
    if value is None:
        return None
    if not _finite(value):
        raise InputError(f"{source}: {key} must be a finite number, not {value!r}")
    return float(value)


def target_from_dict(d: Any, source: str) -> Target:
    if not isinstance(d, dict):
        raise InputError(f"{source}: a target is a JSON object with id, type, inner_corners, square_mm, "
                         "marker_mm, dictionary and first_marker")
    unknown = sorted(set(d) - set(FIELDS))
    if unknown:
        raise InputError(f"{source}: unknown field {unknown[0]!r}; a target has {', '.join(FIELDS)}")
    first = d.get("first_marker", 0)
    if not (_whole(first) and first >= 0):
        raise InputError(f"{source}: first_marker must be a whole number 0 or more, not {first!r}")
    board_fields = {k: d[k] for k in ("type", "inner_corners", "square_mm", "marker_mm", "dictionary") if k in d}
    return Target(
        id=str(d.get("id", "")),
        board=board_from_dict(board_fields, source),
        first_marker=int(first),
        square_mm_uncertainty_um=_optional_number(d, "square_mm_uncertainty_um", source),
        scale_ppm=_optional_number(d, "scale_ppm", source),
    )


def targets_from_list(items: Any, source: str = "session.json targets") -> list[Target]:
    """The targets of a session, checked (unique ids, disjoint marker ranges within each dictionary)."""
    if not isinstance(items, list):
        raise InputError(f"{source}: targets must be a list of target objects (SPEC 13)")
    targets = [target_from_dict(d, f"{source}[{j}]") for j, d in enumerate(items)]
    check_targets(targets, dictionary_sizes(targets))
    return targets


def dictionary_sizes(targets: list[Target]) -> dict[str, int]:
    """Marker counts of the dictionaries in use (OpenCV knows them; names it does not are caught at detection).

    cv2 is imported here, where it is used: io/session imports this module, and `lps estimate` starts
    without OpenCV.
    """
    import cv2

    sizes: dict[str, int] = {}
    for t in targets:
        name = t.board.dictionary or ""
        code = getattr(cv2.aruco, name or "DICT_5X5_1000", None)
        if isinstance(code, int):
            sizes[name] = int(cv2.aruco.getPredefinedDictionary(code).bytesList.shape[0])
    return sizes


def target_to_dict(t: Target) -> dict[str, Any]:
    d: dict[str, Any] = {"id": t.id}
    d.update(board_to_dict(t.board))
    d["first_marker"] = t.first_marker
    if t.square_mm_uncertainty_um is not None:
        d["square_mm_uncertainty_um"] = t.square_mm_uncertainty_um
    if t.scale_ppm is not None:
        d["scale_ppm"] = t.scale_ppm
    return d


def targets_to_list(targets: list[Target]) -> list[dict[str, Any]]:
    return [target_to_dict(t) for t in targets]


def session_targets(meta: dict[str, Any], source: str = "session.json") -> list[Target] | None:
    """The session's targets, or None for a single-board session; both named is an error (SPEC 13)."""
    if "targets" not in meta:
        return None
    if meta.get("board") is not None:
        raise InputError(f"{source}: has both board and targets; a session names one board or a list of targets")
    return targets_from_list(meta["targets"], f"{source} targets")
