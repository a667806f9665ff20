"""Results panel: the report's figures drawn live, tables, the clicked view, export.

Figures come from :func:`lps_gui.report.figures.plots.figures_from_results` (the
same definitions the PDF paints) and tables from ``lps_gui.report.pages.summary``,
so the screen and the paper show the same numbers.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from lps_gui.gui.capture.mounted_targets import MountedTargetsView
from lps_gui.gui.results.plot_adapter import DrawnFigure, ReadableAxis, figure_steps
from lps_gui.gui.results.section_tabs import SectionPage, tab_tip
from lps_gui.gui.results.view_detail import ViewDetail
from lps_gui.gui.widgets import TextTable, ValueTable
from lps_gui.gui.workers import Job, owned_by
from lps_gui.io.results.keys import DEVIATION_UM, MEASURED_MM
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Position
from lps_gui.report.figures.plots import figures_from_results, position_columns
from lps_gui.report.pages.content import SectionContent
from lps_gui.report.registry import tab_contents

log = logging.getLogger(__name__)

CSV_FILES = ("positions.csv", "summary.csv")
TAB_NAMES = {"positions": "Positions", "deviation": "Deviation", "step": "Steps", "straightness": "Straightness",
             "angles": "Roll/pitch/yaw", "residuals": "Residuals", "spectrum": "Spectrum"}
GROUPS = (("Deviation", ("deviation", "positions")), ("Steps", ("step", "spectrum")),
          ("Straightness, angles", ("straightness", "angles")))  # one tab each: all tabs fit without arrows
CLICKABLE = {"positions": ("target_mm", MEASURED_MM), "deviation": ("target_mm", DEVIATION_UM),
             "residuals": ("index", "rms_px")}


class ResultsPanel(QWidget):
    """Plots, ISO 230-2 and position tables of one estimation; export to PDF and CSV."""

    export_requested = Signal(str)  # "pdf" or "csv"; the main window asks for a path and runs it
    failed = Signal(str, str)  # title, one line: something the operator asked for could not be done
    drawing_done = Signal()  # every figure and table of the latest results is drawn

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.results: Results | None = None
        self.session_dir: Path | None = None
        self.results_dir: Path | None = None
        self.drawn: dict[str, DrawnFigure] = {}
        self._corners: Any = None  # (CornerTable, object points), a reason string, or None: not read yet
        self._corners_job: Job | None = None
        self._pending_view: int | None = None
        self._queue: list[Any] = []
        self._pending_table = False
        self._tab_keys: list[str] = []
        self.section_pages: dict[str, SectionPage] = {}  # tab title -> page, built on first use
        self._holders: dict[QWidget, QWidget] = {}  # a stack of plots -> the scroll area that is its tab
        self._generation = 0

        self.header = QLabel("No results yet: run an estimation or open a session with results.json.")
        self.header.setWordWrap(True)
        self.pdf_btn = QPushButton("Export PDF…")
        self.csv_btn = QPushButton("Export CSV…")
        self.open_report_btn = QPushButton("Open report")
        self.open_report_btn.setToolTip("Open the exported PDF report in the system's viewer")
        self.report_path: Path | None = None
        for b in (self.pdf_btn, self.csv_btn, self.open_report_btn):
            b.setEnabled(False)
        top = QVBoxLayout()  # the header wraps above the buttons: a narrow results dock keeps them all in view
        top.addWidget(self.header)
        buttons = QHBoxLayout()
        for b in (self.pdf_btn, self.open_report_btn, self.csv_btn):
            buttons.addWidget(b)
        buttons.addStretch(1)
        top.addLayout(buttons)
        self.verdict = QLabel("")
        self.verdict.setWordWrap(True)
        self.verdict.setTextFormat(Qt.TextFormat.RichText)

        self.tabs = QTabWidget()
        self.tabs.setDocumentMode(True)
        self.tabs.setUsesScrollButtons(True)  # whole titles; a narrow panel scrolls the bar instead of eliding
        self.tabs.tabBar().setElideMode(Qt.TextElideMode.ElideNone)
        self.plots: dict[str, pg.PlotWidget] = {}
        self._pages: dict[str, QWidget] = {}  # figure key -> the tab page showing its plot
        self._groups: dict[str, QSplitter] = {}
        self.iso_table = ValueTable(["Figure", "Value", "U (k = 2)", "Unit"], numeric=(1, 2), stretch=0)
        self.target_label = QLabel("ISO 230-2 per target")
        self.target_label.setWordWrap(True)
        self.target_table = TextTable(numeric=range(0, 20))
        self.accuracy_page = QSplitter(Qt.Orientation.Vertical)  # the figures, then the per-target table
        targets = QWidget()
        tl = QVBoxLayout(targets)
        tl.setContentsMargins(0, 4, 0, 0)
        tl.addWidget(self.target_label)
        tl.addWidget(self.target_table, 1)
        self.accuracy_page.addWidget(self.iso_table)
        self.accuracy_page.addWidget(targets)
        self.mounted_targets = MountedTargetsView()  # a row's targets (SPEC 13)
        self.accuracy_page.addWidget(self.mounted_targets)
        self.accuracy_page.setSizes([300, 200, 150])
        for w in (self.target_label, self.target_table):
            w.setVisible(False)  # until results with ISO 230-2 figures come
        self.position_table = TextTable(numeric=range(1, 30))
        self.detail = ViewDetail()
        split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.tabs)
        split.addWidget(self.detail)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 1)
        split.setCollapsible(0, False)
        split.setSizes([1, 0])  # the figures get the whole width: the clicked view opens beside them on a click
        self.split = split
        self._header_text = ""  # the header without the stale-report note (set_report adds or drops that)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(6, 6, 6, 6)
        lay.addLayout(top)
        lay.addWidget(self.verdict)
        lay.addWidget(split, 1)
        empty = figures_from_results(None)
        self._build_tabs(empty)
        for fig in empty:  # titles and axis labels from the start: the operator sees what will come
            for step in figure_steps(self.plots[fig.key].getPlotItem(), replace(fig, series=[]))[1]:
                step()
        self.pdf_btn.clicked.connect(lambda: self.export_requested.emit("pdf"))
        self.csv_btn.clicked.connect(lambda: self.export_requested.emit("csv"))
        self.open_report_btn.clicked.connect(self.open_report)

    # ------------------------------------------------------------------ showing
    def show_lightfield(self, folder: Path | str) -> None:
        """A "Light field" tab with the folder's EPIs and epipolar numbers (replacing an earlier one), selected; its
        title and content are the registry's (``report/registry.FOLDER_SECTIONS``)."""
        from lps_gui.gui.results.lightfield import LightFieldPage
        from lps_gui.report.registry import folder_section

        page = getattr(self, "lightfield_page", None)
        if page is None:
            page = self.lightfield_page = LightFieldPage()
        page.load(folder, "lightfield")  # an InputError leaves the tabs as they were
        if self.tabs.indexOf(page) < 0:
            self.tabs.addTab(page, folder_section("lightfield").title)
        self.tabs.setCurrentWidget(page)

    def set_results(self, results: Results | dict[str, Any], session_dir: Path | None = None,
                    results_dir: Path | None = None) -> None:
        """Show ``results``: header at once, then one figure per event-loop turn.

        Drawing a figure takes tens of milliseconds; drawing them in separate
        turns keeps the window responsive (:attr:`drawing_done` when all are up).
        ``session_dir`` gives images, corners and truth.
        """
        results = as_results(results)
        self.results = results
        self.session_dir = Path(session_dir) if session_dir else None
        self.results_dir = Path(results_dir) if results_dir else self.session_dir
        self._corners = None
        self._pending_view = None
        self.detail.clear()  # the previous session's view does not stay beside these results
        meta = self._session_meta()
        spec = meta.get("stage_spec") or results.stage_spec
        figures = with_limits(figures_from_results(results, meta.get("truth")), spec)
        self._build_tabs(figures)
        for page in set(self._pages.values()):
            tips = [f.notes or f.title for f in figures if self._pages.get(f.key) is page]
            self.tabs.setTabToolTip(self.tabs.indexOf(self._holders.get(page, page)), "\n".join(tips))
        self.tabs.setCurrentWidget(self.accuracy_page)  # the answer first: accuracy figures and verdict
        scroll_home(self)  # tables and plots start at their left edge, not where the last results were scrolled
        self.drawn.clear()
        self._header(results)
        self.verdict.setText(verdict_html(results, spec))
        for b in (self.pdf_btn, self.csv_btn):
            b.setEnabled(True)
        report = self.session_dir / "report.pdf" if self.session_dir else None
        self.set_report(report if report is not None and report.is_file() else None)
        # the visible figure first, then the others, then the tables
        current = self.tabs.currentIndex()
        order = sorted(range(len(figures)), key=lambda i: self.tabs.indexOf(
            self._holders.get(self._pages[figures[i].key], self._pages[figures[i].key])) != current)
        self._queue = []
        for i in order:
            self._queue += self._draw_steps(figures[i])
        self._queue += self._section_steps(results)
        self._queue += [lambda: self._fill_tables(results), lambda: self._fill_positions(results)]
        self._generation += 1
        generation = self._generation
        QTimer.singleShot(0, self, lambda: self._drain(generation))  # dropped with the panel

    def _drain(self, generation: int) -> None:
        if generation != self._generation:
            return  # newer results replaced these
        if self._queue:
            step = self._queue.pop(0)
            try:
                step()
            except Exception:  # one broken figure or table must not stop the others
                log.exception("results: drawing step failed")
        if self._queue:
            QTimer.singleShot(0, self, lambda: self._drain(generation))
        else:
            self.drawing_done.emit()

    @property
    def drawing(self) -> bool:
        return bool(self._queue) or self._pending_table

    def _build_tabs(self, figures: list[Any]) -> None:
        """One plot per figure key, built once (later results reuse them: no relayout, no new widgets).

        Related figures share a tab (:data:`GROUPS`, stacked), so the accuracy page, the plots and the
        position table all fit in the tab bar.
        """
        keys = [f.key for f in figures]
        if keys == self._tab_keys:
            return
        self.tabs.clear()
        self._pages.clear()
        self.tabs.addTab(self.accuracy_page, "Accuracy")
        for fig in figures:
            if fig.key not in self.plots:
                self.plots[fig.key] = pg.PlotWidget(background="w", axisItems={"bottom": ReadableAxis("bottom")})
        for fig in figures:
            if fig.key in self._pages:
                continue
            title, members = next(((t, [k for k in g if k in keys]) for t, g in GROUPS if fig.key in g),
                                  (TAB_NAMES.get(fig.key, fig.title), [fig.key]))
            if len(members) == 1:
                page: QWidget = self.plots[fig.key]
                title = TAB_NAMES.get(fig.key, fig.title)
            else:
                page = self._groups.setdefault(title, QSplitter(Qt.Orientation.Vertical))
                for k in members:
                    page.addWidget(self.plots[k])
                page.setStretchFactor(0, 3)  # the group's main figure first and larger
                page.setStretchFactor(1, 2)
            for k in members:
                self._pages[k] = page
            self.tabs.addTab(self.tab_holder(page) if len(members) > 1 else page, title)
        self.tabs.addTab(self.position_table, "Table")
        self._tab_keys = keys

    def _section_steps(self, results: Results) -> list[Any]:
        """Steps adding the tabs of the sections these results have (error motions, an ASME test) before "Table".

        The old section tabs go at once; results without the sections keep the tab bar as it was.
        Reading the sections, each tab and each plot are steps of their own (the window stays responsive).
        """
        for page in self.section_pages.values():
            if (i := self.tabs.indexOf(self.tab_holder(page))) >= 0:
                self.tabs.removeTab(i)

        def expand() -> None:
            steps: list[Any] = []
            for content in tab_contents(results):  # the registry's sections with a tab
                steps.append(lambda c=content: self._add_section(c))
                steps += [lambda c=content, i=i, fig=fig: self._run_next(self._section_figure_steps(c, i, fig))
                          for i, fig in enumerate(content.figures)]
            self._run_next(steps)

        return [expand]

    def _run_next(self, steps: list[Any]) -> None:
        self._queue[0:0] = steps

    def _add_section(self, content: SectionContent) -> None:
        page = self.section_pages.setdefault(content.title, SectionPage())
        page.set_content(content)
        index = self.tabs.insertTab(self.tabs.indexOf(self.position_table), self.tab_holder(page), content.title)
        self.tabs.setTabToolTip(index, tab_tip(content))

    def _section_figure_steps(self, content: SectionContent, index: int, fig: Any) -> list[Any]:
        plot = self.section_pages[content.title].plot_for(index, fig.key)
        drawn, steps = figure_steps(plot.getPlotItem(), fig)
        return steps + [lambda: self.drawn.__setitem__(fig.key, drawn)]

    def show_figure(self, key: str) -> None:
        """Bring the tab holding figure ``key`` to the front."""
        page = self._pages.get(key) or next(p for p in self.section_pages.values() if key in p.plots)
        self.tabs.setCurrentWidget(self._holders.get(page, page))

    def tab_holder(self, page: QWidget) -> QWidget:
        """The tab of a stack of plots: a scroll area, so plots that need more height than the tab has scroll
        down instead of losing their data area (each plot keeps its minimum height, plot_adapter.fit_legend)."""
        holder = self._holders.get(page)
        if holder is None:
            from PySide6.QtWidgets import QFrame, QScrollArea

            area = QScrollArea()
            area.setWidgetResizable(True)
            area.setFrameShape(QFrame.Shape.NoFrame)
            area.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
            area.setWidget(page)
            holder = self._holders[page] = area
        return holder

    def _draw_steps(self, fig: Any) -> list[Any]:
        drawn, steps = figure_steps(self.plots[fig.key].getPlotItem(), fig)

        def done() -> None:
            self.drawn[fig.key] = drawn
            for item in drawn.items + drawn.outliers:
                item.sigPointsClicked.connect(lambda _item, points, _ev, key=fig.key: self._clicked(key, points))

        return steps + [done]

    def _header(self, results: Results) -> None:
        p = results.parameters
        n_out = sum(r.outlier for r in results.positions)
        single = results.figures.single_run
        maxdev = single.max_abs_deviation_um if single else None
        self._header_text = (
            f"<b>{results.method or '?'}</b> on {self.session_dir.name if self.session_dir else 'results'}: "
            f"{len(results.positions)} positions, {'?' if p.n_used is None else p.n_used} used, {n_out} outlier view(s); "
            f"RMS {_f(p.rms_px)} px"
            + (f"; peak deviation {_f(maxdev)} µm" if maxdev is not None else "")
            + ("<br><i>outliers beyond an axis are drawn at its edge</i>" if n_out else ""))
        self.header.setText(self._header_text)

    def _session_meta(self) -> dict[str, Any]:
        if self.session_dir is None:
            return {}
        try:
            from lps_gui.io.session import Session

            return Session.open(self.session_dir).meta
        except Exception:  # a results file without its session still plots
            return {}

    # ------------------------------------------------------------------ report
    def set_report(self, path: Path | None) -> None:
        """The PDF that "Open report" opens (after an export, or the session's report.pdf); stale ones say so."""
        self.report_path = Path(path) if path else None
        self.open_report_btn.setEnabled(self.report_path is not None)
        tip = "Open the exported PDF report in the system's viewer"
        header = self._header_text
        if self.report_path is not None and self.session_dir is not None:
            from lps_gui.io.results.history import stale_report_message

            if self.report_path == self.session_dir / "report.pdf" and (stale := stale_report_message(self.session_dir)):
                tip = stale
                header += "<br><i>report.pdf is older than these results: export the PDF again</i>"
        self.header.setText(header)  # an export after the note takes it away again
        self.open_report_btn.setToolTip(tip)

    def open_report(self) -> bool:
        """Open :attr:`report_path` with the desktop's PDF viewer."""
        from PySide6.QtCore import QUrl
        from PySide6.QtGui import QDesktopServices

        if self.report_path is None or not self.report_path.is_file():
            self.failed.emit("Report not opened", "open report: no report.pdf yet; export the PDF first")
            return False
        if not QDesktopServices.openUrl(QUrl.fromLocalFile(str(self.report_path))):
            self.failed.emit("Report not opened", f"{self.report_path}: no PDF viewer opened it; install one "
                                                  "(e.g. evince or okular) or open the file from a file manager")
            return False
        return True

    def _fill_tables(self, results: Results) -> None:
        from lps_gui.report.pages.summary import summary_rows
        from lps_gui.report.registry import figure_table

        self._fill_targets(results)
        self.mounted_targets.set_results(results)
        own_rows = figure_table(results)  # a section with a report of its own (planar); None: the line's rows
        if own_rows is not None:
            self.iso_table.set_rows(own_rows)
            return
        rows = summary_rows(results)
        self.iso_table.set_rows([(r.name, r.text(), r.u_text(), r.unit) for r in rows])
        self._grey_unresolved(rows)

    def _fill_targets(self, results: Results) -> None:
        """The ISO 230-2 per-target table of the report (mean, s, R each way, reversal B), hidden without one."""
        from lps_gui.report.pages.iso_table import iso_target_table

        table = iso_target_table(results)
        for w in (self.target_label, self.target_table):
            w.setVisible(table is not None)
        if table is not None:
            header, rows = table[0], table[1]
            self.target_table.set_rows(header, rows)
            self.target_label.setText(f"ISO 230-2 per target: {len(rows)} targets (\u00b5m; P\u2c7c in mm)")

    def _grey_unresolved(self, rows: list[Any]) -> None:
        """A figure the data do not resolve reads "not resolved (σ X)" in grey, never as a finding."""
        from PySide6.QtGui import QBrush, QColor

        grey = QBrush(QColor("#888888"))
        for i, r in enumerate(rows):
            if getattr(r, "unresolved", ""):
                for c in range(self.iso_table.columnCount()):
                    item = self.iso_table.item(i, c)
                    if item is not None:
                        item.setForeground(grey)
                        item.setToolTip(r.unresolved)

    def _fill_positions(self, results: Results) -> None:
        """Format the per-position table on a worker thread (hundreds of rows), then show it."""
        from lps_gui.report import registry

        self._pending_table = True
        job = owned_by(Job("format positions", lambda: registry.position_table(results), pass_progress=False), self)
        job.succeeded.connect(lambda table, r=results: self._show_positions(table, r))
        job.finished.connect(lambda: setattr(self, "_pending_table", False))
        job.start()

    def _show_positions(self, table: tuple[list[str], list[list[str]]], results: Results) -> None:
        if results is self.results:
            header, body = table
            self.position_table.set_rows([h.replace("\n", " ") for h in header], body)

    # ------------------------------------------------------------------ clicking a point
    def _clicked(self, key: str, points: Any) -> None:
        if not len(points) or key not in CLICKABLE or self.results is None:
            return
        pos = points[0].pos()
        self.show_view_at(key, float(pos.x()), float(pos.y()))

    def show_view_at(self, key: str, x: float, y: float) -> int | None:
        """Show the capture nearest to the plotted point (x, y) of figure ``key``; its index."""
        assert self.results is not None
        cols = position_columns(self.results)
        cx, cy = (cols[c] for c in CLICKABLE[key])
        sx = np.nanstd(cx) or 1.0
        sy = np.nanstd(cy) or 1.0
        d = np.hypot((cx - x) / sx, (cy - y) / sy)
        if not np.isfinite(d).any():
            return None
        i = int(np.nanargmin(d))
        return self.show_view(int(cols["index"][i]))

    def show_view(self, index: int) -> int | None:
        """Show capture ``index`` with its residual vectors.

        The session's corners are read once, on a worker thread (corners.vnl
        of a long session has hundreds of thousands of lines); the view
        fills in when they arrive.
        """
        assert self.results is not None
        rows = [r for r in self.results.positions if r.index == index]
        if not rows:
            return None
        row = rows[0]
        if self._corners is None and self.session_dir is not None:
            self.detail.show_view(self.session_dir, self.results, row, None, None)
            self._open_detail()
            self._pending_view = index
            if self._corners_job is None:
                self._corners_job = owned_by(Job("read corners", load_corners, self.session_dir, pass_progress=False),
                                             self)
                folder = self.session_dir
                self._corners_job.succeeded.connect(lambda res, d=folder: self._corners_loaded(res, d))
                self._corners_job.failed.connect(lambda msg, _tb, d=folder: self._corners_loaded(msg, d))
                self._corners_job.finished.connect(self._corners_job_done)
                self._corners_job.start()
            return index
        detected, X = self._detected(row)
        self.detail.show_view(self.session_dir, self.results, row, detected, X)
        self._open_detail()
        return index

    def _open_detail(self) -> None:
        """The clicked view beside the figures, a third of the width (collapsed until a point is clicked)."""
        sizes = self.split.sizes()
        if sizes[1] == 0:
            total = sum(sizes)
            self.split.setSizes([total - total // 3, total // 3])

    def _corners_loaded(self, loaded: Any, folder: Path) -> None:
        if folder != self.session_dir:
            return  # another session is on screen now
        self._corners = loaded  # (CornerTable, object points) or the one-line reason there are none
        if isinstance(loaded, str):
            log.info("results: no corners to show (%s)", loaded)
        if self._pending_view is not None and self.results is not None:
            index, self._pending_view = self._pending_view, None
            self.show_view(index)

    def _corners_job_done(self) -> None:
        self._corners_job = None

    def _detected(self, row: Position) -> tuple[np.ndarray | None, np.ndarray | None]:
        if not isinstance(self._corners, tuple):
            return None, None
        table, X = self._corners
        name = row.file or ""
        idx = table.index()
        i = idx.get(name, idx.get(Path(name).name))
        return (None, None) if i is None else (table.corners_px[i], X)

    # ------------------------------------------------------------------ export
    def export_csv(self, folder: Path) -> list[Path]:
        """Copy positions.csv and summary.csv written by the estimation into ``folder``."""
        from lps_gui.errors import InputError

        if self.results_dir is None:
            raise InputError("export: no results to export; run an estimation first")
        from lps_gui.io.file_set import write_file_set

        folder = Path(folder)
        files = {}
        for name in CSV_FILES:
            src = self.results_dir / name
            if not src.exists():
                raise InputError(f"{src}: not found; run the estimation again to write the CSV files")
            if src.resolve() != (folder / name).resolve():
                files[name] = src.read_bytes()
        write_file_set(folder, files)  # checked, all or nothing (a full disk leaves no half export)
        return [folder / name for name in CSV_FILES]


def scroll_home(root: QWidget) -> None:
    """Every scroll area under ``root`` back at its left edge (each new result starts unscrolled)."""
    from PySide6.QtWidgets import QAbstractScrollArea

    for area in root.findChildren(QAbstractScrollArea):
        area.horizontalScrollBar().setValue(0)


def with_limits(figures: list[Any], spec: dict[str, Any] | None) -> list[Any]:
    """The figures with the accuracy limit drawn on the deviation plot (as on the report's page 1)."""
    from lps_gui.report.figures.plots import with_spec_band

    limit = (spec or {}).get("accuracy_um")
    if limit is None:
        return figures
    plus_minus = str(spec.get("limits", "plus_minus")) == "plus_minus"
    return [with_spec_band(f, float(limit), plus_minus) if f.key == "deviation" else f for f in figures]


def verdict_html(results: Results, spec: dict[str, Any] | None) -> str:
    """One line per specification row, coloured like the report's verdict."""
    from html import escape

    from lps_gui.report.pages.summary import fmt, session_flags
    from lps_gui.io.results.verdict_rows import session_verdicts
    from lps_gui.report.pages.verdict import overall

    rows = session_verdicts(results, spec)  # a plane's per-axis rows too, as page 1 and results.json
    parts = [f"<b>{overall(rows)}</b>"]
    parts += [f"<span style='color:#c00000'>{escape(m)}</span>" for m in session_flags(results)]  # e.g. the lens model
    for v in rows:
        u = f" \u00b1 {fmt(v.u_k2)}" if v.u_k2 is not None else ""
        parts.append(f"<span style='color:{v.color}'>{v.name}: {fmt(v.measured)}{u} {v.unit} "
                     f"(limit {fmt(v.limit)} {v.unit}) \u2014 <b>{v.verdict}</b></span>")
    return "<br>".join(parts)


def load_corners(session_dir: Path) -> tuple[Any, np.ndarray]:
    """The session's corner table and board points (shape (N, 3) mm), for the view detail."""
    from lps_gui.io.corners.vnl import read_corners_vnl
    from lps_gui.io.session import Session

    session = Session.open(session_dir)
    board = session.board()
    return read_corners_vnl(session.corners_path, board.n_corners), board.object_points()


def _f(v: Any) -> str:
    try:
        return f"{float(v):.3g}"
    except (TypeError, ValueError):
        return "?"
