"""results.json, positions.csv and summary.csv (SPEC 7).

results.json is the complete, versioned record (schema in
docs/ARCHITECTURE.md), assembled here only (:func:`assemble_results`); the
CSVs are views of it for spreadsheets (:func:`summary_csv_rows` gives summary.csv's
rows). All three are written as one set (:func:`lps_gui.io.file_set.write_file_set`):
each to a checked temp file, then renamed together, results.json last, so a
full disk leaves the old set whole and a reader never sees a results.json
whose CSVs are from another run.
"""
from __future__ import annotations

import csv
import io
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui import __version__
from lps_gui.errors import InputError, LpsError
from lps_gui.io.file_set import JOURNAL, recover_file_set, write_file_set
from lps_gui.io.jsonfile import json_bytes, read_json
from lps_gui.io.results.keys import PLANAR_POSITION_COLUMNS, POSITION_COLUMNS
from lps_gui.io.results.typed_json import finite_number

FORMAT = "lps-results/1"
SECTIONS = (  # results.json's sections in schema order: the one definition (builders write in any order)
    "format", "software", "created", "method", "axes", "settings", "inputs", "board", "targets", "intrinsics",
    "session_meta", "parameters", "positions", "figures", "flags", "timings_s", "truth_comparison", "summary",
    "error_motions", "environment", "uncertainty", "asme_b5_64", "verdict",
)
RESULTS_FILE = "results.json"
POSITIONS_FILE = "positions.csv"
SUMMARY_FILE = "summary.csv"
ERROR_MOTION_COLUMNS = (  # SPEC 14: after the columns above, in results that have error_motions
    "eax_urad",
    "ebx_urad",
    "ecx_urad",
    "eax_sigma_urad",
    "ebx_sigma_urad",
    "ecx_sigma_urad",
)


def json_float(x: Any) -> float | None:
    """A float for results.json: NaN and inf become null."""
    x = float(x)
    return x if math.isfinite(x) else None


def json_floats(values: Any) -> list[float | None]:
    """:func:`json_float` of every element of a 1-D array, at numpy speed (a results.json column)."""
    a = np.asarray(values, dtype=float).reshape(-1)
    out: list[float | None] = a.tolist()
    for i in np.flatnonzero(~np.isfinite(a)).tolist():
        out[i] = None
    return out


def in_section_order(sections: dict[str, Any]) -> dict[str, Any]:
    """A new results document with ``sections`` in :data:`SECTIONS`' order; a section not named there is a
    builder's error (its place would be wherever it happened to be written)."""
    unknown = [k for k in sections if k not in SECTIONS]
    if unknown:
        raise ValueError(f"results.json section(s) {unknown} not in io.results.document.SECTIONS; add them there")
    return {k: sections[k] for k in SECTIONS if k in sections}


def rows_from_columns(columns: dict[str, list[Any]]) -> list[dict[str, Any]]:
    """``[{key: column[i] for key in columns} for i]`` with the keys in ``columns``' order."""
    keys = list(columns)
    return [dict(zip(keys, values)) for values in zip(*columns.values())]


def assemble_results(
    *,
    method: str,
    settings: dict[str, Any],
    inputs: dict[str, Any],
    board: dict[str, Any],
    intrinsics: dict[str, Any],
    session_meta: dict[str, Any],
    parameters: dict[str, Any],
    positions: list[dict[str, Any]],
    figures: dict[str, Any],
    flags: list[dict[str, Any]],
    timings_s: dict[str, float],
    truth_comparison: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The results.json document from its parts, in schema order; ``summary`` in its place, empty: its rows are
    summary.csv's view of the finished document (:func:`summary_csv_rows`), made once every section is in it.

    ``truth_comparison`` only for simulated sessions (the key is then present).
    """
    results: dict[str, Any] = {
        "format": FORMAT,
        "software": {"name": "lps-calib", "version": __version__},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "method": method,
        "settings": settings,
        "inputs": inputs,
        "board": board,
        "intrinsics": intrinsics,
        "session_meta": session_meta,
        "parameters": parameters,
        "positions": positions,
        "figures": figures,
        "flags": flags,
        "timings_s": timings_s,
    }
    if truth_comparison is not None:
        results["truth_comparison"] = truth_comparison
    results["summary"] = []
    return results


@dataclass(frozen=True)
class SummaryFigure:
    """One summary figure: its summary.csv name, its report label (None: summary.csv only), value, unit."""

    key: str
    label: str | None
    value: Any
    unit: str = ""
    digits: int = 3  # significant digits when printed
    unresolved: str = ""  # "not resolved (noise p-v X)": noise alone could give the value (core.resolution); no finding


MU = "\u00b5"
ISO_NAMES = {"A": "Accuracy A", "R": "Repeatability R", "E": "Systematic deviation E", "B": "Reversal error B",
             "M": "Mean deviation range M"}
ISO_DIRECTIONS = (("", "bidirectional"), ("_up", "forward \u2191"), ("_down", "backward \u2193"), ("_mean", "mean"))
# truth_comparison key -> (summary.csv name, report label, unit); other numeric keys keep their own words
TRUTH_FIGURES = {
    "position_rms_error_um": ("truth_position_rms_error", "Truth: position error RMS", MU + "m"),
    "position_max_abs_error_um": ("truth_position_max_abs_error", "Truth: position error max |e|", MU + "m"),
    "mean_sigma_um": ("truth_mean_sigma", "Truth: mean position \u03c3 (noise)", MU + "m"),
    "median_sigma_um": ("truth_median_sigma", "Truth: median position \u03c3 (noise)", MU + "m"),
    "z_mean_square": ("truth_z_mean_square", "Truth: mean (error/\u03c3)\u00b2", ""),
    "board_plane_rms_error_um": ("truth_board_plane_rms_error", "Truth at the board plane: position error RMS", MU + "m"),
    "board_plane_max_abs_error_um": ("truth_board_plane_max_abs_error", "Truth at the board plane: position error max |e|",
                                     MU + "m"),
    "board_plane_z_mean_square": ("truth_board_plane_z_mean_square", "Truth at the board plane: mean (error/\u03c3)\u00b2", ""),
    "abbe_rms_um": ("truth_abbe_term_rms", "Truth: Abbe term (board plane - camera centre) RMS", MU + "m"),
    "straightness_rms_error_um_1": ("truth_straightness_rms_error_1", "Truth: straightness v1 error RMS (board plane)",
                                    MU + "m"),
    "straightness_rms_error_um_2": ("truth_straightness_rms_error_2", "Truth: straightness v2 error RMS (board plane)",
                                    MU + "m"),
    "straightness_z_mean_square_1": ("truth_straightness_z_mean_square_1", "Truth: straightness v1 mean (error/\u03c3)\u00b2", ""),
    "straightness_z_mean_square_2": ("truth_straightness_z_mean_square_2", "Truth: straightness v2 mean (error/\u03c3)\u00b2", ""),
    "image_rotation_rms_error_urad": ("truth_image_rotation_rms_error", "Truth: image rotation error RMS", MU + "rad"),
    "image_rotation_z_mean_square": ("truth_image_rotation_z_mean_square", "Truth: image rotation mean (error/\u03c3)\u00b2", ""),
}


def iso_label(key: str) -> str:
    """``"E_up_um"`` -> ``"Systematic deviation E (up)"``; unknown keys keep their words."""
    words = (key[:-3] if key.endswith("_um") else key).split("_")
    if words[0] in ISO_NAMES:
        return f"{ISO_NAMES[words[0]]} ({' '.join(words[1:])})" if len(words) > 1 else ISO_NAMES[words[0]]
    return " ".join(words)


def iso_figures(iso: dict[str, Any] | None) -> list[SummaryFigure]:
    """ISO 230-2 figures in A, R, E, B, M order, each bidirectional, forward, backward, mean; then unknown keys."""
    if not iso:
        return []
    out: list[SummaryFigure] = []
    seen = set()
    for letter, name in ISO_NAMES.items():
        for suffix, words in ISO_DIRECTIONS:
            key = f"{letter}{suffix}_um"
            if key in iso:
                seen.add(key)
                if finite_number(iso[key]) is not None:
                    out.append(SummaryFigure(f"iso230_2_{key[:-3]}", f"ISO 230-2 {name} ({words})", finite_number(iso[key]), MU + "m"))
    for key, value in iso.items():
        if key in seen or key.startswith("n_") or finite_number(value) is None:
            continue
        out.append(SummaryFigure(f"iso230_2_{key.removesuffix('_um')}", f"ISO 230-2 {iso_label(key)}", finite_number(value),
                                 MU + "m" if key.endswith("_um") else ""))
    return out


def resolved_extreme_figures(results: dict[str, Any]) -> list[SummaryFigure] | None:
    """Straightness, image rotation and angles with their resolution (results with ``figures["straightness"]``).

    A figure that noise alone could produce carries "not resolved (noise p-v X)"
    (or "noise max X" for a max |x|): printed instead of the value, never a finding.
    """
    from lps_gui.core.metrology.resolution import not_resolved_text

    figs = results.get("figures") or {}
    st = figs.get("straightness")
    if not isinstance(st, dict):
        return None

    def fig(key: str, label: str, d: dict[str, Any], value_key: str, noise_key: str, unit: str) -> SummaryFigure:
        what = "noise max" if noise_key.startswith("noise_max") else "noise p-v"
        text = "" if d.get("resolved") else not_resolved_text(finite_number(d.get(noise_key)), unit, what=what)
        return SummaryFigure(key, label, finite_number(d.get(value_key)), unit, unresolved=text)

    out = [fig(f"straightness_span_{k}", f"Max straightness v{k} (peak-to-valley)", st.get(f"v{k}") or {}, "span_um",
               "noise_span_um", MU + "m") for k in (1, 2)]
    rot = figs.get("image_rotation")
    if isinstance(rot, dict):
        out.append(fig("image_rotation_span", "Image rotation (peak-to-valley)", rot, "span_urad", "noise_span_urad",
                       MU + "rad"))
    angles = figs.get("angles_resolution") or {}
    for name in ("roll", "pitch", "yaw"):
        out.append(fig(f"max_abs_{name}", f"Max |{name}|", angles.get(name) or {}, "max_abs_urad", "noise_max_abs_urad",
                       MU + "rad"))
    return out


def extreme_figures(results: dict[str, Any]) -> list[SummaryFigure]:
    """Peak-to-valley straightness v1/v2 and max |roll|, |pitch|, |yaw| over the positions not flagged."""
    resolved = resolved_extreme_figures(results)
    if resolved is not None:
        return resolved
    rows = [r for r in results.get("positions") or [] if not r.get("outlier")]

    def column(key: str) -> list[float]:
        return [v for v in (finite_number(r.get(key)) for r in rows) if v is not None]

    from lps_gui.core.metrology.resolution import not_resolved_text

    out = []
    motions = (results.get("error_motions") or {}).get("motions") or {}
    for k, iso in ((1, "EYX"), (2, "EZX")):
        v = column(f"straightness_um_{k}")
        if not v and isinstance(motions.get(iso), dict):  # a row: straightness only from the stops' poses (issue 37)
            out.append(error_motion_straightness(k, iso, motions[iso], bool(results["error_motions"].get(
                "resolved", {}).get(iso))))
            continue
        out.append(SummaryFigure(f"straightness_span_{k}", f"Max straightness v{k} (peak-to-valley)",
                                 max(v) - min(v) if v else None, MU + "m"))
    for name, iso in (("roll", "EAX"), ("pitch", "EBX"), ("yaw", "ECX")):
        v = column(f"{name}_urad")
        if not v and isinstance(motions.get(iso), dict):  # a row: the angles only from the stops' poses (issue 37)
            m = motions[iso]
            text = "" if results["error_motions"].get("resolved", {}).get(iso) else not_resolved_text(
                finite_number(m.get("noise_span_urad")), MU + "rad")
            out.append(SummaryFigure(f"{name}_span_error_motions", f"{name.capitalize()} {iso} (peak-to-valley, error "
                                     "motions)", finite_number(m.get("span_urad")), MU + "rad", unresolved=text))
            continue
        out.append(SummaryFigure(f"max_abs_{name}", f"Max |{name}|", max(abs(x) for x in v) if v else None, MU + "rad"))
    return out


def error_motion_straightness(k: int, iso: str, motion: dict[str, Any], resolved: bool) -> SummaryFigure:
    """Straightness v``k`` of a session whose only straightness is the error motion ``iso`` (a row of targets):
    its p-v over the targets, "not resolved (noise p-v X)" below its noise."""
    from lps_gui.core.metrology.resolution import not_resolved_text

    text = "" if resolved else not_resolved_text(finite_number(motion.get("noise_span_um")), MU + "m")
    return SummaryFigure(f"straightness_span_{k}", f"Straightness {iso} (peak-to-valley, error motions)",
                         finite_number(motion.get("span_um")), MU + "m", unresolved=text)


def periodic_figures(single: dict[str, Any]) -> list[SummaryFigure]:
    """Periodic error amplitude and period; "not defined" (no value, no U) where the plan resolves no period
    (:func:`lps_gui.core.metrology.iso230_spectrum.resolvable_band`) though captures exist."""
    from lps_gui.core.metrology.iso230_spectrum import UNDEFINED_TEXT

    amplitude = finite_number(single.get("periodic_amplitude_um"))
    undefined = UNDEFINED_TEXT if amplitude is None and single.get("n_captures") else ""
    return [SummaryFigure("periodic_amplitude", "Periodic error amplitude", amplitude, MU + "m", unresolved=undefined),
            SummaryFigure("periodic_period", "Periodic error period", None if undefined else
                          finite_number(single.get("periodic_period_mm")), "mm", unresolved=undefined)]


def summary_figures(results: dict[str, Any]) -> list[SummaryFigure]:
    """Every summary figure of a results document, in report order: the one builder of summary.csv,
    the report's summary table and the GUI's (via ``report.summary.summary_rows``)."""
    p = results.get("parameters") or {}
    figs = results.get("figures") or {}
    single = figs.get("single_run") or {}
    out = [
        SummaryFigure("method", None, results.get("method")),
        SummaryFigure("views", None, p.get("n_views")),
        SummaryFigure("views_used", None, p.get("n_used")),
        SummaryFigure("outlier_views", None, p.get("n_outliers")),
        SummaryFigure("corner_noise_sigma", None, p.get("sigma_px"), "px"),
        SummaryFigure("rms_reprojection", None, p.get("rms_px"), "px"),
        *([SummaryFigure("rms_reprojection_at_board", "RMS reprojection error at the board",
                         finite_number(p.get("rms_um_at_board")), MU + "m")] if "rms_um_at_board" in p else []),
        SummaryFigure("mean_step", "Mean step", finite_number(single.get("mean_step_mm")), "mm", digits=7),
        SummaryFigure("step_std", "Step std", finite_number(single.get("step_std_um")), MU + "m"),
        SummaryFigure("max_abs_deviation", "Max |deviation|", finite_number(single.get("max_abs_deviation_um")), MU + "m"),
        SummaryFigure("scale", "Scale error", finite_number(single.get("scale_ppm")), "ppm"),
        SummaryFigure("scale_sigma", "Scale error \u03c3 (noise, correlations included)", finite_number(single.get("scale_sigma_ppm")), "ppm"),
        SummaryFigure("scale_sigma_total", "Scale error \u03c3 (total, with intrinsics)", finite_number(single.get("scale_sigma_total_ppm")),
                      "ppm"),
    ] + periodic_figures(single)
    out += iso_figures(figs.get("iso230_2"))
    out += extreme_figures(results)
    angles = figs.get("angles_resolution") or {}
    for name, value in (figs.get("angles_span_urad") or {}).items():  # no finding where the angle is not resolved
        unresolved = "not resolved" if name in angles and not (angles[name] or {}).get("resolved") else ""
        out.append(SummaryFigure(f"{name}_span", None, value, MU + "rad", unresolved=unresolved))
    for key, value in (results.get("truth_comparison") or {}).items():
        if finite_number(value) is None:
            continue
        csv_name, label, unit = TRUTH_FIGURES.get(
            key, (f"truth_{key.removesuffix('_um')}", f"Truth: {key.removesuffix('_um').replace('_', ' ')}",
                  MU + "m" if key.endswith("_um") else ""))
        out.append(SummaryFigure(csv_name, label, finite_number(value), unit))
    out.append(SummaryFigure("software_version", None, (results.get("software") or {}).get("version")))
    return out


U_KEYS = {"step_std": "step_std_um", "max_abs_deviation": "max_abs_deviation_um", "scale": "scale_ppm",
          "periodic_amplitude": "periodic_amplitude_um"}  # summary figure -> results uncertainty.figures_k2
SUMMARY_COLUMNS = ("name", "value", "unit", "u_k2", "note")  # U (k = 2) in the row's unit; note: "not resolved ..."


def u_key(key: str) -> str:
    """The ``uncertainty.figures_k2`` key of a summary figure (core.uncertainty_budget.figure_uncertainties)."""
    if key.startswith("iso230_2_"):
        return key.removeprefix("iso230_2_") + "_um"
    if key.startswith(("straightness_span_", "max_abs_", "image_rotation_span")) and key != "max_abs_deviation":
        return key
    return U_KEYS.get(key, key)


def figure_u_k2(results: dict[str, Any], key: str) -> float | None:
    """U (k = 2) of a summary figure in its printed unit, from results ``uncertainty.figures_k2`` and nowhere else
    (the mean step's is stored in um and printed in mm); None when not assessed."""
    k2 = (results.get("uncertainty") or {}).get("figures_k2") or {}
    if key == "mean_step":
        u = finite_number(k2.get("mean_step_um"))
        return None if u is None else 1e-3 * u
    return finite_number(k2.get(u_key(key)))


def summary_csv_rows(results: dict[str, Any]) -> list[tuple[Any, ...]]:
    """(name, value, unit, U (k = 2), note) rows of summary.csv: every figure of :func:`summary_figures` with a
    value, then the verdict rows (``results["verdict"]``, when the session has a stage specification).

    An unresolved figure keeps its row with an empty value and no U, its note saying why ("not resolved (noise
    p-v X)": noise alone could give it, no finding), and so does a figure the plan does not define.
    """
    rows: list[tuple[Any, ...]] = [
        (f.key, None if f.unresolved else f.value, f.unit.replace(MU, "u"),
         None if f.unresolved else figure_u_k2(results, f.key), f.unresolved.replace(MU, "u"))
        for f in summary_figures(results) if f.value is not None or f.unresolved]
    return rows + verdict_csv_rows(results.get("verdict"))


def verdict_csv_rows(verdict: dict[str, Any] | None) -> list[tuple[Any, ...]]:
    """summary.csv's verdict: the overall word, the decision rule, then one ``check_*`` row per specified figure."""
    if not isinstance(verdict, dict):
        return []
    rows: list[tuple[Any, ...]] = [("verdict", verdict.get("overall"), "", None, verdict.get("overall_text", "")),
                                   ("decision_rule", verdict.get("decision_rule"), "", None, "")]
    for c in verdict.get("checks") or []:
        unit = str(c.get("unit") or "").replace(MU, "u")
        limit = finite_number(c.get("limit"))
        note = f"{c.get('verdict')}; {c.get('quantity') or 'figure'} against the limit {_fmt(limit)} {unit}".strip()
        rows.append((f"check_{c.get('key')}", finite_number(c.get("measured")), unit, finite_number(c.get("u_k2")),
                     note + (f"; {c['note']}" if c.get("note") else "")))
    return rows


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return "" if value != value else f"{value:.6g}"
    return str(value)


def position_columns(results: dict[str, Any]) -> tuple[str, ...]:
    """The positions.csv columns: SPEC 7 for a line, SPEC 10 for a planar session, then SPEC 14's angles.

    Results from before the error motions (no ``error_motions``) keep their columns.
    """
    base = PLANAR_POSITION_COLUMNS if len(results.get("axes") or ["X"]) == 2 else POSITION_COLUMNS
    return base + ERROR_MOTION_COLUMNS if "error_motions" in results else base


_CSV_SPECIAL = frozenset(',"\r\n')


def _fmt_column(values: list[Any]) -> tuple[list[str], bool]:
    """:func:`_fmt` of every value, and whether any cell needs the csv module's quoting."""
    out = [f"{v:.6g}" if type(v) is float and v == v else _fmt(v) for v in values]  # the common case inlined
    plain = all(type(v) is float or v is None or isinstance(v, (bool, int)) for v in values)
    return out, not plain and any(not _CSV_SPECIAL.isdisjoint(cell) for cell in out)


def positions_csv(results: dict[str, Any]) -> str:
    """positions.csv: the columns of :func:`position_columns`, a row per position (csv's quoting where needed)."""
    columns = position_columns(results)
    rows = results["positions"]
    cells, quote = [], False
    for c in columns:
        column, special = _fmt_column([row.get(c) for row in rows])
        cells.append(column)
        quote |= special
    if quote or not all(_CSV_SPECIAL.isdisjoint(c) for c in columns):
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(columns)
        w.writerows(zip(*cells))
        return buf.getvalue()
    return "".join(",".join(line) + "\n" for line in [columns, *zip(*cells)])


def summary_csv(results: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(SUMMARY_COLUMNS)
    for row in results.get("summary", []):
        cells = [_fmt(v) for v in row] + [""] * (len(SUMMARY_COLUMNS) - len(row))
        w.writerow(cells[:len(SUMMARY_COLUMNS)])
    return buf.getvalue()


def write_results(folder: Path | str, results: dict[str, Any]) -> dict[str, Path]:
    """Write the three result files into ``folder``; returns their paths.

    A ``folder`` ending in ``.json`` names the results file itself; its CSVs
    go beside it as ``<stem>-positions.csv`` and ``<stem>-summary.csv``.
    """
    folder, names = _result_names(Path(folder))
    written = write_file_set(folder, result_set_bytes(results, names), last=names["results"])
    return {key: written[name] for key, name in names.items()}


def result_set_bytes(results: dict[str, Any], names: dict[str, str] | None = None) -> dict[str, bytes]:
    """The content of the result set: ``{file name: bytes}`` of positions.csv, summary.csv and results.json."""
    names = names or {"positions": POSITIONS_FILE, "summary": SUMMARY_FILE, "results": RESULTS_FILE}
    return {
        names["positions"]: positions_csv(results).encode("utf-8"),
        names["summary"]: summary_csv(results).encode("utf-8"),
        names["results"]: json_bytes(results),
    }


def result_set_paths(path: Path | str) -> list[Path]:
    """The three files :func:`write_results` writes for ``path`` (so a caller can check each before the write)."""
    folder, names = _result_names(Path(path))
    return [folder / name for name in names.values()]


def _result_names(path: Path) -> tuple[Path, dict[str, str]]:
    if path.suffix.lower() != ".json" or path.is_dir():
        return path, {"positions": POSITIONS_FILE, "summary": SUMMARY_FILE, "results": RESULTS_FILE}
    if path.name == RESULTS_FILE:
        return path.parent, {"positions": POSITIONS_FILE, "summary": SUMMARY_FILE, "results": RESULTS_FILE}
    return path.parent, {"positions": f"{path.stem}-{POSITIONS_FILE}", "summary": f"{path.stem}-{SUMMARY_FILE}",
                         "results": path.name}


def read_results_document(path: Path | str) -> tuple[Path, dict[str, Any]]:
    """(the file, its JSON object) of results.json (a folder is taken to hold one), after a killed commit is finished.

    The file as data; :func:`lps_gui.io.results.model.read_results` reads it into typed sections (and checks them).
    """
    path = Path(path)
    if path.is_dir():
        path = path / RESULTS_FILE
    if not path.exists():
        raise InputError(f"{path}: no results yet; run `lps estimate {path.parent}` first")
    if (path.parent / JOURNAL).exists():  # a writer was killed mid-commit: finish it, so the set read is one set
        try:
            recover_file_set(path.parent)
        except LpsError:  # a read-only copy: read what is there
            pass
    data = read_json(path, "results file", follow_symlinks=False)  # lps writes it, never as a link
    if not isinstance(data, dict):
        raise InputError(f"{path}: not an {FORMAT} file (not a JSON object); re-run `lps estimate`")
    if data.get("format") != FORMAT:
        raise InputError(f"{path}: not an {FORMAT} file ('format' is {data.get('format')!r}); re-run `lps estimate`")
    return path, data
