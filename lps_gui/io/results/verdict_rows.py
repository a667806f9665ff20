"""The verdict rows of any results document: a line's, or a plane's per-axis and squareness rows.

One list for page 1, the GUI, results.json ``verdict`` and summary.csv. Here, below both the pipeline (which
writes the verdict into results.json) and the report (which prints it): the rows and the decision rule are
``core.metrology.verdict``'s; what this module adds is reading a planar document per axis, each axis shaped
like a line session's results (its ISO 230-2 figures, its U), and the U (k = 2) of every planar figure page 1
prints (:func:`planar_figure_us`: the report's rows and summary.csv read the same numbers).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from lps_gui.core.metrology.decision_rule import decide
from lps_gui.core.metrology.resolution import not_resolved_text
from lps_gui.core.metrology.verdict import (
    FAIL_COLOR,
    GREY,
    PASS_COLOR,
    Verdict,
    verdicts,
)
from lps_gui.errors import InputError
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Figures, SpanResolution
from lps_gui.io.results.typed_json import finite_number

SQUARENESS_CHECK = "Squareness"  # stage_spec ``squareness_urad``: the limit on |squareness| (no halving: an angle)


def figure_u(k2: Mapping[str, Any], key: str, sigma: float | None) -> float | None:
    """U (k = 2) of a planar figure: results.json ``uncertainty.figures_k2`` when it has it, else 2 sigma (noise)."""
    u = finite_number(k2.get(key))
    return u if u is not None else (None if sigma is None else 2.0 * float(sigma))


def planar_figures_k2(results: Results | dict[str, Any]) -> dict[str, Any]:
    """U (k = 2) of the planar figures: a top-level ``uncertainty.figures_k2``, or each axis's budget's scale U.

    A plane's budget is per axis (``uncertainty.per_axis``); each axis's scale U
    is that axis's ``scale_x_ppm`` / ``scale_y_ppm``, the squareness has a
    row of its own and keeps its noise U.
    """
    unc = as_results(results).uncertainty
    if unc is None:
        return {}
    k2 = dict(unc.figures_k2)
    for axis, axis_unc in unc.per_axis.items():
        if axis in ("X", "Y") and axis_unc.figures_k2.get("scale_ppm") is not None:
            k2.setdefault(f"scale_{axis.lower()}_ppm", axis_unc.figures_k2["scale_ppm"])
    return k2


def axis_figures_k2(results: Results, axis: str) -> Mapping[str, Any]:
    """U (k = 2) of one axis's figures: that axis's budget (``uncertainty.per_axis``), else the top-level one."""
    unc = results.uncertainty
    if unc is None:
        return {}
    axis_unc = unc.per_axis.get(axis)
    return axis_unc.figures_k2 if axis_unc is not None else unc.figures_k2


def unresolved_text(span: SpanResolution | None) -> str:
    """"not resolved (noise p-v X)" for a p-v that noise alone could give (core.resolution), else empty."""
    if span is None or span.resolved is None or span.resolved:
        return ""
    return not_resolved_text(span.noise_span_um, "\u00b5m")


def planar_figure_us(results: Results | dict[str, Any]) -> dict[str, tuple[float | None, str]]:
    """(U (k = 2), "not resolved ..." or "") of each planar figure by the key page 1's rows carry: the
    squareness (also in um/m), the scales, each axis's straightness in and out of the plane and its worst
    line's ISO 230-2 A, R, E, B. An unresolved figure has no U (never one smaller than its noise)."""
    results = as_results(results)
    pl = results.figures.planar
    if pl is None:
        return {}
    k2 = planar_figures_k2(results)
    u_sq = figure_u(k2, "squareness_urad", pl.squareness_sigma_urad)
    out: dict[str, tuple[float | None, str]] = {
        "squareness_urad": (u_sq, ""), "squareness_um_per_m": (u_sq, ""),
        "scale_x_ppm": (figure_u(k2, "scale_x_ppm", pl.scale_x_sigma_ppm), ""),
        "scale_y_ppm": (figure_u(k2, "scale_y_ppm", pl.scale_y_sigma_ppm), "")}
    for axis, other in (("X", "Y"), ("Y", "X")):
        a = pl.per_axis.get(axis)
        if not a:
            continue
        ax, ot = axis.lower(), other.lower()
        axis_k2 = axis_figures_k2(results, axis)
        unresolved = unresolved_text(a.straightness)
        out[f"straightness_{ax}_along_{ot}_max"] = (
            None if unresolved else finite_number(axis_k2.get("straightness_span_max")), unresolved)
        if a.out_of_plane:
            out[f"out_of_plane_straightness_{ax}_max"] = (None, unresolved_text(a.out_of_plane))
        iso = a.iso230_2.iso230_2 if a.iso230_2 else None
        for key in ("A_um", "R_um", "E_um", "B_um"):
            if iso and iso.number(key) is not None:  # U from that axis's budget, the U its verdict row compares
                out[f"iso230_2_{ax}_{key[:-3]}"] = (finite_number(axis_k2.get(key)), "")
    return out


def axis_results(results: Results | dict[str, Any], axis: str) -> Results | None:
    """One axis of a planar session shaped like a line session's results (its ISO 230-2 figures, its U), or None.

    What the line report's verdict and per-target sections read: ``figures``
    (that axis's ``iso230_2`` block plus its straightness) and ``uncertainty``
    (``uncertainty.per_axis[axis]`` when the results carry one).
    """
    results = as_results(results)
    pl = results.figures.planar
    a = pl.per_axis.get(axis) if pl else None
    if a is None or a.iso230_2 is None or a.iso230_2.iso230_2 is None:
        return None
    figures = Figures.from_dict({**a.iso230_2.raw, "straightness_um_max": a.straightness_um_max,
                                 "straightness_sigma_um": a.straightness_sigma_um},
                                f"figures.planar.per_axis.{axis}.iso230_2", results.source)
    unc = results.uncertainty.per_axis.get(axis) if results.uncertainty else None
    return replace(results, figures=figures, uncertainty=unc)


def planar_verdicts(results: Results, spec: dict[str, Any]) -> list[Verdict]:
    """The verdict rows of a planar session: each axis's line rows ("X: Positional accuracy", from that axis's
    ISO 230-2 figures and its U) and, when the specification gives ``squareness_urad``, the squareness row
    (|squareness| with the U page 1's geometry table prints, one decision rule)."""
    rows = [replace(v, name=f"{axis}: {v.name}") for axis in "XY" if (ar := axis_results(results, axis)) is not None
            for v in verdicts(ar, spec)]
    limit = spec.get("squareness_urad")
    if limit is None:
        return rows
    try:
        limit = float(limit)
    except (TypeError, ValueError):
        raise InputError(f"stage spec: squareness_urad must be a number in \u00b5rad, got {limit!r}") from None
    pl = results.figures.planar
    measured = None if pl is None or pl.squareness_urad is None else abs(float(pl.squareness_urad))
    u = None if pl is None else figure_u(planar_figures_k2(results), "squareness_urad", pl.squareness_sigma_urad)
    word = decide(measured, limit, None if measured is None else measured <= limit, u)
    note = "|angle +X to +Y minus 90\u00b0| against the limit"
    if word == "not resolved":
        note = f"the limit lies within \u00b1U of the figure (ISO 14253-1); {note}"
    return rows + [Verdict(SQUARENESS_CHECK, measured, u, limit, "\u00b5rad", word,
                           {"PASS": PASS_COLOR, "FAIL": FAIL_COLOR}.get(word, GREY), note, "|squareness|")]


def session_verdicts(results: Results | dict[str, Any], spec: dict[str, Any] | None) -> list[Verdict]:
    """The verdict rows of ``results`` against a stage specification (empty without one)."""
    if not spec:
        return []
    results = as_results(results)
    return planar_verdicts(results, spec) if results.planar else verdicts(results, spec)
