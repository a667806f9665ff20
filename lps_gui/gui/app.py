"""``lps-gui``: start the operator's window, or render it offscreen to a PNG.

``lps-gui --screenshot PATH [--session DIR]`` opens the window (loading the
session's results.json if given), renders it offscreen, saves a PNG and
exits, so the README's screenshots are made by the program itself.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="lps-gui", description="lps-calib operator GUI (PySide6).")
    p.add_argument("--session", type=Path, help="open this session folder (and show its results.json)")
    p.add_argument("--screenshot", type=Path, metavar="PATH", help="render the window offscreen to PATH (PNG) and exit")
    p.add_argument("--size", default="1600x1000", help="window size WxH for --screenshot (default 1600x1000)")
    p.add_argument("--settings", type=Path, help="keep settings in this INI file instead of the user's")
    return p


def make_app(argv: list[str] | None = None):  # -> QApplication
    """The QApplication with our names and pyqtgraph's row-major images (created once)."""
    import pyqtgraph as pg
    from PySide6.QtWidgets import QApplication

    from lps_gui.gui.main_window import APPLICATION, ORGANIZATION

    pg.setConfigOptions(imageAxisOrder="row-major", antialias=False)
    app = QApplication.instance() or QApplication(argv or [sys.argv[0]])
    app.setOrganizationName(ORGANIZATION)
    app.setApplicationName(APPLICATION)
    app.setWindowIcon(app_icon())
    return app


def app_icon():  # -> QIcon
    """The application icon with every raster size, so each desktop picks a crisp one."""
    from PySide6.QtGui import QIcon

    from lps_gui.resources import app_icon_paths

    icon = QIcon()
    for path in app_icon_paths():
        icon.addFile(str(path))
    return icon


def make_settings(path: Path | None):  # -> QSettings
    from PySide6.QtCore import QSettings

    from lps_gui.gui.main_window import APPLICATION, ORGANIZATION

    if path is not None:
        return QSettings(str(path), QSettings.Format.IniFormat)
    return QSettings(ORGANIZATION, APPLICATION)


def settle(widget, timeout_s: float = 30.0) -> None:
    """Process events until deferred drawing (results figures) is done and the layout is final."""
    import time

    from PySide6.QtWidgets import QApplication

    end = time.monotonic() + timeout_s
    results = getattr(getattr(widget, "window", lambda: None)(), "results_panel", None)
    while time.monotonic() < end:
        QApplication.processEvents()
        if results is None or not results.drawing:
            break
    for _ in range(5):
        QApplication.processEvents()


def render_to_png(window, path: Path, size: tuple[int, int] | None = None) -> Path:
    """Lay out ``window`` at ``size``, let it paint, and save what it shows."""
    if size:
        window.resize(*size)
    window.show()
    settle(window)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not window.grab().save(str(path)):
        from lps_gui.errors import InputError

        raise InputError(f"{path}: cannot write the PNG; check the folder and the .png suffix")
    return path


def main(argv: list[str] | None = None) -> int:
    from lps_gui.blas_threads import limit_blas_threads

    limit_blas_threads()  # before anything imports numpy
    from lps_gui.allocator import tune_allocator

    args = build_parser().parse_args(argv)
    tune_allocator()
    if args.screenshot is not None:
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    app = make_app()
    from lps_gui.errors import InputError, LpsError
    from lps_gui.gui.main_window import MainWindow

    settings = make_settings(args.settings)
    if args.screenshot is not None and args.settings is None:
        import tempfile

        from PySide6.QtCore import QSettings

        # a screenshot shows the default layout, whatever the user rearranged
        settings = QSettings(str(Path(tempfile.mkdtemp()) / "screenshot.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings)
    try:
        if args.session is not None:
            if not args.session.is_dir():
                raise InputError(f"{args.session}: session folder not found; check the path")
            window.open_session(args.session)
            if args.screenshot is not None and window.last_error is not None:
                raise InputError(window.last_error[1])
        if args.screenshot is not None:
            w, h = (int(v) for v in args.size.lower().split("x"))
            out = render_to_png(window, args.screenshot, (w, h))
            print(out)
            window.shutdown()
            return 0
    except LpsError as exc:
        print(f"lps-gui: {exc}", file=sys.stderr)
        window.shutdown()
        return 2
    window.show()
    return app.exec()


if __name__ == "__main__":
    sys.exit(main())
