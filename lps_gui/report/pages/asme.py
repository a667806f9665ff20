"""Report pages of the ASME B5.64 tests (results.json ``asme_b5_64``); no Qt here (the flow paints).

:func:`names_note` goes under the ISO 230-2 figures of every line report (the
same figures under their ASME B5.64 names); :func:`test_pages` adds a page
for a session that ran the incremental-step or the settling test, with the
test uncertainty ratio of every specified figure.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import AsmeB564, AsmeFigure, IncrementalStep, Settling, UncertaintyRatio
from lps_gui.report.figures.asme import settling_figure, step_figure, test_figures
from lps_gui.report.figures.spec import FigureSpec
from lps_gui.report.pages.content import SectionContent
from lps_gui.report.pages.summary import fmt

GREY = "#555555"
NOTE_SIZE = 7.5
FIGURE_HEIGHT_MM = 78.0
RECORD_MARGIN = 1.5  # a settling record should run this many times the settling time
TUR_NOTE = ("Test uncertainty ratio (ASME B5.64): the specification's tolerance over the expanded uncertainty U "
            "(k = 2) of the figure as it is compared with it (a \u00b1 limit against half a band, as in the verdict). "
            "A figure without a tolerance in the stage specification has no ratio; 4 or more is the usual aim.")


def section(results: Results | Mapping[str, Any]) -> AsmeB564:
    """results.json ``asme_b5_64`` (empty for results without it)."""
    return as_results(results).asme_b5_64 or AsmeB564()


def names_note(flow: Any, results: Results | Mapping[str, Any]) -> None:
    """One paragraph: the ISO 230-2 figures of these results under their ASME B5.64 names."""
    rows = section(results).figures
    if not rows:
        return
    parts = [f"{r.symbol} = {r.asme_b5_64}" for r in rows]
    note(flow, "ASME B5.64 names the same figures: " + "; ".join(parts) + ".")


def has_test(results: Results | Mapping[str, Any]) -> bool:
    return section(results).has_test


def section_figures(results: Results) -> list[FigureSpec]:
    """The figures of the test a session ran (steps, settling); [] for none."""
    return test_figures(section(results))


def asme_content(results: Results, figures: list[FigureSpec]) -> SectionContent:
    """The "ASME B5.64" tab, for a session that ran the incremental-step or the settling test: its ``figures``
    (:func:`section_figures`), the findings and the test uncertainty ratios."""
    rows = tur_cells(section(results).test_uncertainty_ratio)
    lines = finding_lines(results) + ([] if rows else ["No tolerance in session.json stage_spec: no test "
                                                       "uncertainty ratio is stated."])
    return SectionContent("ASME B5.64", figures, lines, TUR_HEADER, rows)


def test_pages(flow: Any, results: Results | Mapping[str, Any], figure_height_mm: float = FIGURE_HEIGHT_MM) -> None:
    """The test's page (new page first); nothing for a session that ran neither test. (The test's figures
    keep their own height, :data:`FIGURE_HEIGHT_MM`: ``figure_height_mm`` is the registry's common signature.)"""
    s = section(results)
    if not s.has_test:
        return
    flow.new_page()
    if s.incremental_step and s.incremental_step.raw:
        incremental_step_section(flow, s.incremental_step)
    if s.settling and s.settling.raw:
        settling_section(flow, s.settling)
    tur_section(flow, s.test_uncertainty_ratio)
    names_table(flow, s.figures)


def step_verdict(step: IncrementalStep) -> str:
    """The test's finding in one sentence."""
    d = ", ".join(f"{fmt(z.commanded_um)}" for z in step.sizes) or "\u2014"
    sigma = step.max_step_sigma_um
    if step.sticks:
        z = next(z for z in step.sizes if z.sticks)
        return (f"The stage sticks: {z.n_stuck} of {z.n_steps} commanded steps of {fmt(z.commanded_um)} \u00b5m "
                f"moved less than half the command (noise alone would make {z.n_stuck_by_noise:.1f}); the steps "
                f"scatter {z.scatter_z2 ** 0.5:.1f} times their \u03c3 about the command (stick-slip or a dead band). "
                f"The minimum incremental motion is larger than {fmt(z.commanded_um)} \u00b5m.")
    if step.minimum_incremental_motion_um is not None:
        return (f"Steps of {fmt(step.minimum_incremental_motion_um)} \u00b5m resolved and achieved: every step's "
                f"\u03c3 \u2264 {fmt(sigma)} \u00b5m ({step.frames_per_stop} frames per stop averaged), "
                f"{step.n_achieved} of {step.n_steps} within \u00b1{100 * step.tolerance:.0f} % of the command "
                f"(U included). Minimum incremental motion \u2264 {fmt(step.minimum_incremental_motion_um)} \u00b5m.")
    if step.n_resolved < step.n_steps:
        return (f"Steps of {d} \u00b5m are not resolved: a step's \u03c3 reaches {fmt(sigma)} \u00b5m, its U (k = 2) "
                "exceeds the step. Average more frames per stop or bring the camera closer.")
    return (f"Steps of {d} \u00b5m resolved but not achieved within \u00b1{100 * step.tolerance:.0f} %: "
            "the minimum incremental motion is larger.")


def incremental_step_section(flow: Any, step: IncrementalStep) -> None:
    flow.heading("ASME B5.64 incremental-step test (minimum incremental motion)", 11)
    flow.paragraph(step_verdict(step), size_pt=9.0)
    flow.figure(step_figure(step), FIGURE_HEIGHT_MM)
    header = ["commanded", "steps", "resolved", "achieved", "below \u00bd", "by noise", "mean step", "median \u03c3"]
    cells = [[f"{fmt(z.commanded_um)} \u00b5m", str(z.n_steps), str(z.n_resolved), str(z.n_achieved),
              str(z.n_stuck), f"{z.n_stuck_by_noise:.1f}", f"{fmt(z.mean_achieved_um)} \u00b5m",
              f"{fmt(step.median_step_sigma_um)} \u00b5m"] for z in step.sizes]
    flow.table(header, cells, [24, 16, 20, 20, 16, 20, 30, 30], size_pt=8.0)
    note(flow, "Each stop is the mean of its frames; a step's \u03c3 is that of the difference of two stop means "
                   "from the estimate's full covariance. Resolved: U (k = 2) below the command. Achieved: within "
                   "the tolerance unless outside it by more than U. Stuck: moved less than half the command.")
    truth = step.truth
    if truth is not None:
        note(flow, f"Simulated stage: dead band {fmt(truth.dead_band_um)} \u00b5m (the truth; not part "
                       "of the measurement).")


def note(flow: Any, text: str) -> None:
    """A grey note under a figure or table (how it was made, the simulator's truth)."""
    flow.paragraph(text, size_pt=NOTE_SIZE, color=GREY)


def settling_section(flow: Any, settling: Settling) -> None:
    flow.heading("ASME B5.64 settling test", 11)
    t = settling.settling_time_s
    if t is None:
        flow.paragraph("No stop had enough frames with their times (captures.jsonl since_move_s) to fit.", color=GREY)
        return
    flow.paragraph(f"Settling time within \u00b1{fmt(settling.band_um)} \u00b5m: {t:.3f} s \u00b1 "
                   f"{settling.settling_time_U_s:.3f} s (U, k = 2), the longest of {settling.n_stops} moves "
                   f"(median {settling.median_settling_time_s:.3f} s); from the frames alone "
                   f"{_seconds(settling.settling_time_frames_s)}.", size_pt=9.0)
    short = [s for s in settling.stops if s.record_s is not None and s.record_s < RECORD_MARGIN * s.settling_time_s]
    if short:
        flow.paragraph(f"The frames of {len(short)} move(s) end within {RECORD_MARGIN:g} times the settling time: the "
                       "fit extrapolates there; take more frames per stop (--frames).", size_pt=8.5, color="#a05a00")
    flow.figure(settling_figure(settling), FIGURE_HEIGHT_MM)
    cells = [[f"{s.target_mm:g} mm {s.direction}", f"{s.settling_time_s:.3f}", f"{s.settling_time_U_s:.3f}",
              _seconds(s.settling_time_frames_s), f"{s.amplitude_um:.1f}", f"{s.frequency_hz:.2f}",
              f"{s.decay_s:.3f}", f"{s.residual_sigma_um:.2f}"] for s in settling.stops]
    flow.table(["move to", "settled [s]", "U [s]", "frames [s]", "A [\u00b5m]", "f [Hz]", "\u03c4 [s]", "\u03c3 [\u00b5m]"],
               cells, [26, 22, 18, 22, 22, 20, 20, 20], size_pt=8.0)
    note(flow, "Time counts from the stage reporting the move done (captures.jsonl since_move_s, at the end of "
                   "each frame's exposure). A damped cosine rest + A e^(\u2212t/\u03c4) cos(2\u03c0ft + \u03c6) is "
                   "fitted to each move's frames; the settling time is the last time the fit is outside the band. "
                   "\"frames\": the first frame after which every frame is inside the band (noise makes it later).")
    truth = settling.truth
    if truth is not None:
        note(flow, f"Simulated stage: rings {fmt(truth.amplitude_um)} \u00b5m at {fmt(truth.frequency_hz)} Hz, "
                       f"decay {fmt(truth.decay_s)} s; true settling time {truth.settling_time_s:.3f} s "
                       "(the truth; not part of the measurement).")


def settling_line(settling: Settling) -> str:
    t = settling.settling_time_s
    if t is None:
        return "settling: no stop had enough timed frames to fit"
    line = (f"settling time within \u00b1{fmt(settling.band_um)} \u00b5m: {t:.3f} s \u00b1 "
            f"{settling.settling_time_U_s:.3f} s (k = 2)")
    truth = settling.truth
    return line + (f"; true {truth.settling_time_s:.3f} s" if truth and truth.raw else "")


def finding_lines(results: Results | Mapping[str, Any]) -> list[str]:
    """The ASME test's findings, one line per test that ran (demo, CLI, the GUI's ASME tab)."""
    return [step_verdict(t) if isinstance(t, IncrementalStep) else settling_line(t) for t in section(results).tests_run]


def test_lines(results: Results | Mapping[str, Any]) -> list[str]:
    """The ASME test's findings and the test uncertainty ratios, one line each (demo, CLI)."""
    from lps_gui.core.metrology.verdict import TEST_ROWS
    from lps_gui.report.pages.verdict import verdicts

    s = section(results)
    lines = finding_lines(results)
    r_all = as_results(results)
    for v in verdicts(r_all, dict(r_all.stage_spec or {})):  # the test's verdict, as page 1 and summary.csv state it
        if v.name in TEST_ROWS:
            lines.append(f"Verdict {v.name}: {v.verdict} against {fmt(v.limit)} {v.unit} ({v.note})")
    for r in s.test_uncertainty_ratio:
        ratio = "\u2014" if r.tur is None else f"{r.tur:.1f}"
        lines.append(f"TUR {r.figure}: {ratio} (tolerance {fmt(r.tolerance)} {r.unit})")
    return lines


def _seconds(v: Any) -> str:
    return "never inside the band" if v is None else f"{float(v):.3f} s"


TUR_HEADER = ["figure", "compared", "tolerance", "U (k = 2)", "TUR"]


def tur_cells(rows: tuple[UncertaintyRatio, ...]) -> list[list[str]]:
    """One row of :data:`TUR_HEADER` per specified figure (the report's table and the GUI's)."""
    return [[r.figure, r.quantity or "", f"{fmt(r.tolerance)} {r.unit}",
             "\u2014" if r.U is None else f"{fmt(r.U)} {r.unit}",
             "\u2014" if r.tur is None else f"{r.tur:.1f}"] for r in rows]


def tur_section(flow: Any, rows: tuple[UncertaintyRatio, ...]) -> None:
    flow.heading("Test uncertainty ratio", 11)
    if not rows:
        flow.paragraph("No tolerance in the stage specification (lps capture --spec ...,min_step=UM,settling=S): "
                       "no ratio is stated.", color=GREY)
        return
    flow.table(TUR_HEADER, tur_cells(rows), [56, 30, 30, 30, 20], size_pt=8.0)
    note(flow, TUR_NOTE)


def names_table(flow: Any, rows: tuple[AsmeFigure, ...]) -> None:
    if not rows:
        return
    flow.heading("ISO 230-2 and ASME B5.64 names", 11)
    cells = [[r.symbol, r.iso230_2, r.asme_b5_64, f"{fmt(r.value_um)} \u00b5m",
              "\u2014" if r.U_um is None else f"{fmt(r.U_um)} \u00b5m"] for r in rows]
    flow.table(["", "ISO 230-2", "ASME B5.64", "value", "U (k = 2)"], cells, [10, 62, 56, 26, 26], size_pt=7.5,
               align_left=(1, 2))
