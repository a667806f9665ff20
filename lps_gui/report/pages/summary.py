"""The text of a report as rows of plain data: title block, figures, pass/fail, limits.

The PDF paints these rows and the tests compare them with results.json, so
every number printed has exactly one source. No Qt here.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from lps_gui.core.estimator.methods import report_text
from lps_gui.core.geometry.camera_model import HIGHER_NAMES, INTRINSIC_NAMES
from lps_gui.core.metrology.digits import DASH, fmt  # noqa: F401  (fmt re-exported: the report prints through it)
from lps_gui.core.metrology.verdict import SpecCheck  # noqa: F401  (re-exported: the report types its rows by it)
from lps_gui.core.metrology.verdict import spec_checks as _spec_checks
from lps_gui.io.results.document import (
    SummaryFigure,
    extreme_figures,
    figure_u_k2,
    iso_figures,
    summary_figures,
    u_key,  # noqa: F401  (re-exported: compare and tests read U by it)
)
from lps_gui.io.results.document import finite_number as _num
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Iso230
from lps_gui.report.figures.plots import TRUTH_AT_MEASUREMENT, position_columns
from lps_gui.io.results.keys import DEVIATION_UM, MEASURED_MM, SIGMA_TOTAL_UM


@dataclass(frozen=True)
class Row:
    """One line of a summary table; ``value`` is None when the data do not allow it."""

    name: str
    value: float | None
    unit: str = ""
    note: str = ""
    digits: int = 3  # significant digits when printed
    unresolved: str = ""  # "not resolved (noise p-v X)": printed instead of a value, greyed (core.resolution)
    key: str = ""  # the figure's key in results.json (for its U)
    u_k2: float | None = None  # expanded uncertainty (k = 2) in ``unit``, None when not assessed
    shown: str = ""  # printed instead of the number when a count reads better as text ("30 / 30")

    def text(self) -> str:
        """The value as printed: ``digits`` significant digits, a dash when absent."""
        return self.unresolved or self.shown or fmt(self.value, self.digits)

    def u_text(self) -> str:
        """U (k = 2) as printed ("\u00b1 0.52"; with the value's decimals when it is far smaller), empty when not assessed."""
        if self.u_k2 is None:
            return ""
        text = fmt(self.u_k2, 2)
        value = self.text()
        if "e" in text and "." in value:  # e.g. a mean step 2.000054 mm +- 0.000086 mm, not 8.6e-05
            text = f"{self.u_k2:.{len(value.split('.')[1])}f}"
        return f"\u00b1 {text}"


# ----------------------------------------------------------------------------- title block


def title_rows(session_meta: dict[str, Any], results: Results | dict[str, Any], version: str) -> list[tuple[str, str]]:
    """(label, text) pairs of the identification block: who, what, with which equipment and software.

    ``session_meta["identification"]`` holds what the operator typed (operator,
    customer, stage_model, stage_serial, controller_serial, location); a
    driver's class name ("RigStage") is printed as words ("simulated stage").
    """
    results = as_results(results)
    camera = session_meta.get("camera") or {}
    stage = session_meta.get("stage") or {}
    ident = session_meta.get("identification") or {}
    board = results.board.raw if results.board else session_meta.get("board") or {}
    corners = board.get("inner_corners") or ["?", "?"]
    sha = results.inputs.sha256 if results.inputs else {}
    session_hash = sha.get("session.json") or sha.get("session") or ""
    truth = session_meta.get("truth")
    rig = session_meta.get("rig") or stage.get("rig") or (f"simulated ({truth.get('preset', 'simulator')})" if truth else DASH)
    intr = results.intrinsics
    size = (intr.image_size if intr else ()) or camera.get("image_size")
    if not size and camera.get("width") and camera.get("height"):
        size = [camera["width"], camera["height"]]
    fx = float(intr.K[0, 0]) if intr and intr.camera_matrix else 0.0
    lens = _describe(camera, ("lens", "focal_length_mm"), "")
    stage_text = _describe({**stage, "model": ident.get("stage_model") or stage.get("model")},
                           ("name", "model", "driver", "kind"), DASH)
    if ident.get("stage_serial"):
        stage_text += f", serial {ident['stage_serial']}"
    axes = stage.get("axes") or results.axes
    if len(axes) > 1:
        stage_text += f", axes {', '.join(str(a) for a in axes)}"
    elif stage.get("axis"):
        stage_text += f", axis {stage['axis']}"
    controller = _describe(stage, ("controller", "firmware", "port"), "simulated (no controller)" if truth else DASH)
    if ident.get("controller_serial"):
        controller += f", serial {ident['controller_serial']}"
    board_text = f"chessboard {corners[0]}\u00d7{corners[1]} inner corners, square {fmt(board.get('square_mm'), 4)} mm at 20 \u00b0C"
    targets = results.targets
    if targets:  # a row or constellation (SPEC 13), or one board moved: the table of targets lists each
        stitched = ((results.session_meta or {}).get("plan") or {}).get("segments")
        board_text = (f"one board in {len(targets)} placements (table of targets): " + board_text if stitched
                      else f"{len(targets)} ChArUco targets (table of targets); T0 " + board_text.split(" ", 1)[1])
    u_sq = results.environment.square_mm_uncertainty_um if results.environment else None
    if u_sq is not None:
        board_text += f", u = {fmt(u_sq, 2)} \u00b5m"
    return [
        ("Date", str(results.created or session_meta.get("created") or DASH)),
        ("Customer", str(ident.get("customer") or "not recorded")),
        ("Operator", str(ident.get("operator") or "not recorded")),
        ("Location", str(ident.get("location") or "not recorded")),
        ("Session", str((results.inputs and results.inputs.session) or DASH)),
        ("Rig", str(rig)),
        ("Stage", stage_text),
        ("Controller", controller),
        ("Camera", _describe(camera, ("name", "model", "driver", "device", "source"), DASH)
         + (f", {size[0]}\u00d7{size[1]} px" if size else "")),
        ("Lens", lens or (f"not recorded; focal length {fx:.1f} px from the intrinsics" if fx else DASH)),
        ("Board", board_text),
        ("Software", f"lps-calib {version}"),
        ("Session hash", f"sha256 {session_hash[:16]}\u2026 (session.json)" if session_hash else DASH),
    ]


CLASS_WORDS = {"RigStage": "simulated stage", "SimStage": "simulated stage", "SimulatedCamera": "simulated camera",
               "SimCamera": "simulated camera"}


def _words(value: Any) -> str:
    """A driver's class name as words: "RigStage" -> "simulated stage", "GrblStage" -> "grbl stage"."""
    text = str(value)
    if text in CLASS_WORDS:
        return CLASS_WORDS[text]
    if re.fullmatch(r"(?:[A-Z][a-z0-9]+){2,}", text):
        return " ".join(w.lower() for w in re.findall(r"[A-Z][a-z0-9]+", text))
    return text


def _describe(d: dict[str, Any], keys: Sequence[str], default: str) -> str:
    parts = [_words(d[k]) for k in keys if d.get(k) not in (None, "", {})]
    return ", ".join(parts) if parts else default


def intrinsics_rows(results: Results | dict[str, Any]) -> list[tuple[str, str, str]]:
    """(name, value, std) of the 9 intrinsics; std a dash when the file has none."""
    intr = as_results(results).intrinsics
    K = intr.K if intr else np.eye(3)
    dist = list(intr.dist if intr else ()) + [0.0] * 5
    values = {"fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2], "k1": dist[0], "k2": dist[1],
              "p1": dist[2], "p2": dist[3], "k3": dist[4]}
    std = intr.std if intr else {}
    out = []
    for name in INTRINSIC_NAMES:
        unit = " px" if name in ("fx", "fy", "cx", "cy") else ""
        out.append((name, (f"{values[name]:.3f}" if unit else fmt(values[name], 4)) + unit, fmt(_num(std.get(name)), 2) + (unit if _num(std.get(name)) is not None else "")))
    higher = dist[5:12] if len(dist) >= 12 + 5 else []  # a rational / thin-prism lens: 12 coefficients (+ the padding)
    out += [(name, fmt(v, 4), "held") for name, v in zip(HIGHER_NAMES, higher) if v]
    return out


def method_rows(results: Results | dict[str, Any]) -> list[tuple[str, str]]:
    """Method, its settings and the fit statistics, as (label, text)."""
    results = as_results(results)
    p = results.parameters.raw
    method = str(results.method or DASH)
    rows = [("Method", report_text(method))]
    for k, v in results.settings.items():
        if k == "method" or (isinstance(v, dict) and k != method):
            continue  # the method is above; another method's options do not apply
        text = ", ".join(f"{a}={b}" for a, b in v.items()) if isinstance(v, dict) else str(v)
        rows.append((f"  {k.replace('_', ' ')}", text if len(text) < 60 else text[:57] + "\u2026"))
    rows += [
        ("Views used / total", f"{p.get('n_used', DASH)} / {p.get('n_views', DASH)}"),
        ("Observations, dof", f"{p.get('n_observations', DASH)}, {p.get('dof', DASH)}"),
        ("RMS residual", f"{fmt(_num(p.get('rms_px')))} px (noise \u03c3 {fmt(_num(p.get('sigma_px')))} px)"),
        ("Iterations", f"{p.get('iterations', DASH)} ({'converged' if p.get('converged') else 'NOT converged'})"),
        ("Intrinsics from", str((results.inputs and results.inputs.intrinsics_source) or DASH)),
    ]
    return rows


# ----------------------------------------------------------------------------- figures


ONE_SIGMA_LABELS = {"scale_sigma": "Scale error 1\u03c3 (noise only, correlations included)",
                    "scale_sigma_total": "Scale error 1\u03c3 (noise and intrinsics)",
                    "truth_mean_sigma": "Truth: mean position 1\u03c3 (noise only)",
                    "truth_median_sigma": "Truth: median position 1\u03c3 (noise only)"}


def _row(f: SummaryFigure) -> Row:
    return Row(ONE_SIGMA_LABELS.get(f.key, f.label or f.key), f.value, f.unit, digits=f.digits, key=f.key,
               unresolved=f.unresolved)


def iso_rows(iso: Iso230 | dict[str, Any] | None) -> list[Row]:
    """ISO 230-2 figures of results.json (``core.iso230.Iso230Figures`` as a dict) as rows.

    Order A, R, E, B, M; each bidirectional, then forward and backward
    (:func:`lps_gui.io.results.document.iso_figures`). Per-target tables and run
    counts are left to the plots and the table; numeric keys we do not know
    are printed with their own words.
    """
    return [_row(f) for f in iso_figures(iso.raw if isinstance(iso, Iso230) else iso)]


def summary_rows(results: Results | dict[str, Any]) -> list[Row]:
    """The summary figures of SPEC 5 as printed in the report, in report order.

    The figures of :func:`lps_gui.io.results.document.summary_figures` (the same
    builder as summary.csv) that have a report label: single-run figures,
    ISO 230-2 figures (absent with one run), maxima of straightness and
    angles over the positions not flagged; the truth comparison is :func:`truth_rows`, on its own page.
    """
    doc = as_results(results).to_dict()
    return [_with_u(doc, _row(f)) for f in summary_figures(doc) if f.label is not None and not f.key.startswith("truth_")]


def truth_rows(results: Results | dict[str, Any]) -> list[Row]:
    """The simulator's truth comparison (simulated sessions only): printed on its own page, labelled."""
    return [_row(f) for f in summary_figures(as_results(results).to_dict())
            if f.label is not None and f.key.startswith("truth_")]


def _with_u(doc: dict[str, Any], row: Row) -> Row:
    """The row with its U (k = 2): :func:`lps_gui.io.results.document.figure_u_k2`, the one reading summary.csv uses.

    A figure printed as "not resolved" carries no U (it states no value to carry one).
    """
    return row if row.unresolved else replace(row, u_k2=figure_u_k2(doc, row.key))


TRUTH_CHECK_KIND = "truth_check"  # results.json flag of a simulated session its truth contradicts (sim/truth_figures)


def truth_check_lines(results: Results | dict[str, Any]) -> list[str]:
    """Page 1's and the console's warning when a simulated session's truth contradicts its report (none else)."""
    flags = [f for f in as_results(results).flags if f.kind == TRUTH_CHECK_KIND]
    if not flags:
        return []
    tc = as_results(results).truth_comparison
    problems = ((tc.get("self_check") or {}).get("problems") or []) if tc else []
    return ["SIMULATED SESSION FAILS ITS TRUTH CHECK: the simulator's truth contradicts this report"] + [
        f"  - {p}" for p in problems or [flags[0].message or ""]]


def view_flags(results: Results) -> list[Any]:
    """The flags of single views (outliers), without the session-level truth check."""
    return [f for f in results.flags if f.kind != TRUTH_CHECK_KIND]


def figure_notes(results: Results | dict[str, Any]) -> list[str]:
    """The caveats the figures carry (e.g. ISO 230-2 asks for 5 runs), each once."""
    figs = as_results(results).figures
    notes: list[str] = []
    for part in (figs.single_run, figs.iso230_2):
        for note in part.notes if part else ():
            if str(note) not in notes:
                notes.append(str(note))
    return notes


def extremes_rows(results: Results | dict[str, Any]) -> list[Row]:
    """Peak-to-valley straightness per direction v1/v2 and max |roll|, |pitch|, |yaw| (outliers excluded)."""
    return [_row(f) for f in extreme_figures(as_results(results).to_dict())]


# ----------------------------------------------------------------------------- specification


def spec_checks(results: Results | dict[str, Any], spec: dict[str, Any] | None) -> list[SpecCheck]:
    """Pass/fail of the stage specification (session.json ``stage_spec``): ``core.metrology.verdict.spec_checks``."""
    return _spec_checks(as_results(results).figures.raw, spec)


# ----------------------------------------------------------------------------- limits


def limits_notes(results: Results | dict[str, Any]) -> list[str]:
    """What limits the result, in words a metrologist signs: board scale, intrinsics, noise."""
    results = as_results(results)
    square_mm = results.board.square_mm if results.board else None
    cols = position_columns(results)
    sig = cols["sigma_um"][np.isfinite(cols["sigma_um"])]
    tot = cols[SIGMA_TOTAL_UM][np.isfinite(cols[SIGMA_TOTAL_UM])]
    notes = [
        "Board scale: every length is measured in units of the board's square size "
        f"({fmt(square_mm, 4)} mm as given). An error in the printed square size is a pure "
        "scale error: a square 0.1 % too large makes every position and the scale error 1000 ppm too large, "
        "and leaves the shape of the deviation curve, the straightness and the angles unchanged. Measure the "
        "board with a calibrated instrument to remove it; its certified uncertainty (the board's "
        "calibration certificate) and its temperature enter the uncertainty budget, and a board away from "
        "20 \u00b0C is corrected with its expansion coefficient.",
    ]
    if sig.size:
        text = (f"Uncertainty per position: noise alone gives a median \u03c3 of {fmt(float(np.median(sig)), 2)} \u00b5m")
        if tot.size:
            text += (f"; with the propagated intrinsics uncertainty the median total \u03c3 is "
                     f"{fmt(float(np.median(tot)), 2)} \u00b5m. The difference is what better intrinsics "
                     "(more varied calibration views) would gain.")
        else:
            text += "; the intrinsics uncertainty was not propagated (no intrinsics covariance given)."
        notes.append(text)
    notes += straightness_notes(results, cols)
    notes.append(
        "Abbe offset: the model holds the camera's orientation constant, so a pitch or yaw of the carriage "
        "about an axis across the motion shifts the image like a translation of (board distance x angle). "
        "The positions are therefore the displacement seen at the board plane, with an Abbe offset equal to the "
        "camera-board distance: 10 \u00b5rad at 600 mm is 6 \u00b5m. The per-view angles above show whether "
        "it matters; a shorter distance reduces it, as a laser interferometer's beam near the tool point does.")
    notes.append("Deviations are relative to the first capture (offset zero there), not to the carriage's "
                 "encoder reading; the first capture's own noise is part of every other position's \u03c3.")
    return notes


def straightness_notes(results: Results, cols: dict[str, np.ndarray]) -> list[str]:
    """What one planar board resolves (SPEC 11): straightness and image rotation yes, the tilts hardly."""
    med = {k: fmt(float(np.median(v[np.isfinite(v)])), 2) if np.isfinite(v).any() else DASH
           for k, v in ((k, cols.get(k, np.array([np.nan]))) for k in (
               "straightness_sigma_um_1", "straightness_sigma_um_2", "roll_sigma_urad", "pitch_sigma_urad",
               "yaw_sigma_urad"))}
    rot = results.column("image_rotation_sigma_urad")
    rot_med = fmt(float(np.median(rot[np.isfinite(rot)])), 2) if np.isfinite(rot).any() else DASH
    st = results.figures.straightness
    if st is None or "constant orientation" not in str(st.basis or ""):
        if DASH in (med["straightness_sigma_um_1"], med["straightness_sigma_um_2"]):  # no per-view straightness
            return ["Straightness and angles: no per-view figures at the board plane in this session; where the "
                    "session resolves them they are on the error motions page. Figures that noise alone could "
                    "produce are shown as \"not resolved\"."]
        return ["Straightness and angles come from each view's own pose, which is far less certain than its "
                f"position along the line: median 1\u03c3 is {med['straightness_sigma_um_1']} \u00b5m (v1) and "
                f"{med['straightness_sigma_um_2']} \u00b5m (v2). Figures that noise alone could produce are shown "
                "as \"not resolved\"."]
    return [
        "Straightness is the displacement of the line of sight at the board plane (the same Abbe convention as "
        "the positions), per view with the common orientation, off a least-squares line: median 1\u03c3 "
        f"{med['straightness_sigma_um_1']} \u00b5m in the board plane across the motion (v1) and "
        f"{med['straightness_sigma_um_2']} \u00b5m along the viewing direction (v2), which the board shows only "
        f"through its image scale. Image rotation (about the optical axis) has a median 1\u03c3 of {rot_med} "
        "\u00b5rad per view. Peak-to-valley figures are taken over the targets (runs and directions averaged) and "
        "are findings only above what noise alone would span (shown beside them); otherwise they read \"not "
        "resolved\". The \u03c3 counts the corner noise; a corner detector's bias that repeats at the same pose is "
        "not in it.",
        "Tilts: a tilt of the camera about an axis parallel to the board shifts the image like a translation of "
        "(distance x angle), so one planar board separates roll and pitch from straightness only through weak "
        f"perspective: per-view 1\u03c3 roll {med['roll_sigma_urad']}, pitch {med['pitch_sigma_urad']}, yaw "
        f"{med['yaw_sigma_urad']} \u00b5rad, shown as \"not resolved\" where noise alone reaches the figure. Their "
        "effect at the board plane is inside the straightness and positions (Abbe offset). A second board at "
        "another distance in the same view would separate them; this version does not support a two-depth target.",
    ]


def session_flags(results: Results | dict[str, Any]) -> list[str]:
    """Flags of the whole session (no view index), e.g. a lens model that does not fit: page 1 shows them."""
    return [f.message or f.kind or "" for f in as_results(results).flags if f.index is None]


def outlier_rows(results: Results | dict[str, Any]) -> list[dict[str, Any]]:
    """Flagged views: index, file, reason, RMS residual; flags without a position row are kept too."""
    results = as_results(results)
    by_index = {r.index: r for r in results.positions}
    rows = {}
    for r in by_index.values():
        if r.outlier:
            rows[r.index] = {"index": r.index, "file": r.file or "", "reason": r.outlier_reason or "flagged",
                             "rms_px": r.number("rms_px")}
    for f in view_flags(results):
        i = -1 if f.index is None else f.index
        pos = by_index.get(i)
        entry = rows.setdefault(i, {"index": i, "file": (pos and pos.file) or "", "reason": "",
                                    "rms_px": pos.number("rms_px") if pos else None})
        msg = f.message or f.kind or ""
        entry["reason"] = msg if not entry["reason"] or entry["reason"] in ("flagged", f.kind) else entry["reason"]
    return [rows[k] for k in sorted(rows)]


POSITION_TABLE_COLUMNS = (  # (key, header, decimals or None for text, width in mm)
    ("index", "#", 0, 9), ("run", "run", 0, 7), ("direction", "dir", None, 6), ("target_mm", "target\n[mm]", 3, 13),
    (MEASURED_MM, "measured\n[mm]", 4, 15), (DEVIATION_UM, "deviation\n[\u00b5m]", 2, 14),
    ("truth_deviation_um", "truth dev.\n[\u00b5m]", 2, 16),
    (SIGMA_TOTAL_UM, "1\u03c3\n[\u00b5m]", 2, 13), ("rms_px", "rms\n[px]", 3, 10),  # the band's sigma (plots)
    ("straightness_um_1", "str. v1\n[\u00b5m]", 2, 13), ("straightness_um_2", "str. v2\n[\u00b5m]", 2, 13),
    ("roll_urad", "roll\n[\u00b5rad]", 1, 13), ("pitch_urad", "pitch\n[\u00b5rad]", 1, 13),
    ("yaw_urad", "yaw\n[\u00b5rad]", 1, 13), ("outlier", "outlier", None, 11),
)


def table_cells(positions: Sequence[Any], columns: Sequence[tuple[str, str, int | None, float]]
                ) -> list[list[str]]:
    """Text cells of a per-position table (rows with ``get``: :class:`Position`): fixed decimals per column,
    a dash when absent, "yes" for outliers."""
    body = []
    for r in positions:
        row = []
        for key, _, decimals, _ in columns:
            v = r.get(key)
            if key == "outlier":
                row.append("yes" if v else "")
            elif decimals is None:
                row.append(str(v if v is not None else DASH))
            else:
                f = _num(v)
                row.append(DASH if f is None else f"{f:.{decimals}f}")
        body.append(row)
    return body


def position_table(results: Results | dict[str, Any]) -> tuple[list[str], list[list[str]], list[float]]:
    """Header, text rows and column widths (mm) of the per-position table (fixed decimals per column).

    The truth column appears only for simulated sessions (results carry ``truth_deviation_um``).
    """
    positions = as_results(results).sorted_positions()
    has_truth = any(r.get("truth_deviation_um") is not None for r in positions)
    columns = [c for c in POSITION_TABLE_COLUMNS if has_truth or c[0] != "truth_deviation_um"]
    if any(r.get(TRUTH_AT_MEASUREMENT) is not None for r in positions):  # like with like: truth at the board plane
        columns = [(TRUTH_AT_MEASUREMENT, "truth dev.\nboard pl.", *c[2:]) if c[0] == "truth_deviation_um" else c
                   for c in columns]
    header = [c[1] for c in columns]
    body = table_cells(positions, columns)
    return header, body, [float(c[3]) for c in columns]
