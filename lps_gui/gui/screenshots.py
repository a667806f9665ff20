"""Make the README's screenshots: ``python -m lps_gui.gui.screenshots docs/screenshots`` (``make screenshots``).

Everything shown is real: the simulated rig is connected and jogged, its
camera previewed, intrinsics calibrated from rendered images, a simulated
session estimated; then the window and each main panel are saved as PNG.
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable

SIZE = (1600, 1000)
PANELS = ("stage", "camera", "intrinsics", "capture", "estimation", "results")


def wait_until(cond: Callable[[], bool], timeout_s: float = 30.0) -> bool:
    from PySide6.QtWidgets import QApplication

    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        QApplication.processEvents()
        if cond():
            return True
        time.sleep(0.01)  # a script, not a test: let worker threads run
    return False


def prepare(window, work: Path) -> None:
    """Bring every panel into a state worth showing."""
    from lps_gui.core.truth.simulate import preset
    from lps_gui.pipeline.estimate import estimate_session
    from lps_gui.pipeline.intrinsics import calibrate_images
    from lps_gui.sim.images import simulate_intrinsics_set
    from lps_gui.sim.points import simulate_point_session

    spec = preset("small", replaced_views=(7,))
    spec = replace(spec, plan=replace(spec.plan, directions="both", runs=2))
    session = work / "session-small"
    simulate_point_session(spec, session)
    estimate_session(session, "joint", {"robust": True})
    window.open_session(session)
    window.results_panel.show_view(7)

    # stage: connect the simulated rig and move it a little
    panel = window.stage_panel
    panel.connect_source()
    wait_until(lambda: window.stage_ctl.connected and window.stage_ctl.last_status is not None)
    panel.feed.setValue(3000.0)
    panel.step.setCurrentIndex(panel.step.findData(10.0))
    panel.jog("X", +1)
    wait_until(lambda: window.stage_ctl.last_status is not None and window.stage_ctl.last_status.work_mm[0] > 9.99
               and window.stage_ctl.last_status.state == "Idle")
    wait_until(lambda: panel.settings_table.rowCount() > 0, 5.0)

    # camera: live preview of the board at the stage's position
    cam = window.camera_panel
    wait_until(lambda: cam.sim_camera is not None)
    cam.start()
    wait_until(lambda: cam.frames_shown >= 3 and cam.detect_label.text().startswith("found"), 30.0)

    # intrinsics: rendered calibration views
    ip = window.intrinsics_panel
    ip.set_board(spec.rig.board)
    paths = simulate_intrinsics_set(work / "intrinsics-set", spec.rig.board, spec.rig.intrinsics, n_views=12, seed=2)
    ip.add_images(paths)
    ip.show_calibration(calibrate_images(paths, spec.rig.board))
    wait_until(lambda: not ip.list.item(len(paths) - 1).icon().isNull(), 10.0)

    # capture: the plan of the session above, into a fresh folder
    window.capture_panel.set_plan(spec.plan)
    window.capture_panel.set_folder(work / "new-session")


def make_screenshots(out_dir: Path) -> list[Path]:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtCore import QSettings

    from lps_gui.gui.app import make_app, render_to_png
    from lps_gui.gui.main_window import MainWindow

    make_app()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="lps-screens-") as tmp:
        work = Path(tmp)
        window = MainWindow(QSettings(str(work / "settings.ini"), QSettings.Format.IniFormat))
        try:
            window.resize(*SIZE)
            window.show()
            window.arrange_docks()  # the first start's layout at this size (offscreen's screen is smaller)
            prepare(window, work)
            window.show_panel("stage")
            rp = window.results_panel
            rp.show_figure("deviation")
            written = [render_to_png(window, out_dir / "main.png")]
            for name in PANELS:
                window.show_panel(name)
                if name == "results":  # the outlier view, found from the residual plot
                    rp.show_figure("residuals")
                wait_until(lambda: False, 0.2)
                written.append(render_to_png(window.docks[name], out_dir / f"{name}.png"))
            for name, show in (("deviation", lambda: rp.show_figure("deviation")),
                               ("angles", lambda: rp.show_figure("angles")), ("steps", lambda: rp.show_figure("step")),
                               ("accuracy", lambda: rp.tabs.setCurrentWidget(rp.accuracy_page))):
                show()
                wait_until(lambda: False, 0.2)
                written.append(render_to_png(window.docks["results"], out_dir / f"results-{name}.png"))
            window.show_panel("stage")
        finally:
            window.shutdown()
    return written


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else Path("docs/screenshots")
    for p in make_screenshots(out):
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
