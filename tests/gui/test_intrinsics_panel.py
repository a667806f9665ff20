"""Intrinsics from the GUI: rendered board images with known truth, calibrate in a worker, save/load."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.truth.simulate import preset
from lps_gui.sim.images import simulate_intrinsics_set

pytestmark = pytest.mark.gui
N_VIEWS = 8


@pytest.fixture(scope="module")
def image_set(tmp_path_factory):
    spec = preset("small")
    paths = simulate_intrinsics_set(tmp_path_factory.mktemp("iset"), spec.rig.board, spec.rig.intrinsics,
                                    n_views=N_VIEWS, seed=3)
    return paths, spec.rig


def test_calibrate_show_save_and_load(qtbot, window, image_set, tmp_path):
    paths, rig = image_set
    panel = window.intrinsics_panel
    panel.set_board(rig.board)
    panel.add_images(paths)
    assert panel.list.count() == N_VIEWS
    qtbot.waitUntil(lambda: not panel.list.item(N_VIEWS - 1).icon().isNull(), timeout=10000)  # thumbnails
    with qtbot.waitSignal(panel.intrinsics_changed, timeout=60000) as got:
        panel.calib_btn.click()
    intr = got.args[0]
    std = intr.std()
    truth = rig.intrinsics.vector()
    # fx, fy, cx, cy recovered within their own reported uncertainty (5 sigma, at least 0.5 px)
    assert np.all(np.abs(intr.vector()[:4] - truth[:4]) < np.maximum(5 * std[:4], 0.5))
    assert panel.table.rowCount() == 12  # 9 intrinsics, the board bow along x and y, the image size
    assert panel.table.cell(0, 0) == "fx" and panel.table.cell(0, 2) != "—" and panel.table.cell(0, 3) == "px"
    assert len(panel.calibration.per_view_rms_px) == N_VIEWS
    assert panel.pictures["Coverage"].image is not None and panel.pictures["Residuals per view"].image is not None
    assert " px" in panel.list.item(0).text()  # per-view error next to each image

    for name in ("cam.json", "cam.yaml"):
        panel.save(tmp_path / name)
        assert (tmp_path / name).exists()
    # the saved file is what the next estimation uses
    assert window.estimation_panel.intrinsics.text() == str(tmp_path / "cam.yaml")
    panel.set_intrinsics(rig.intrinsics)  # something else on screen
    panel.load(tmp_path / "cam.yaml")
    assert np.allclose(panel.intrinsics.vector(), intr.vector(), rtol=1e-6)


def test_calibrate_without_images_says_what_to_do(qtbot, window):
    window.intrinsics_panel.calib_btn.click()
    assert window.last_error is not None
    assert "add calibration images" in window.last_error[1]


def test_pictures_and_cross_validation(qtbot, window, image_set, tmp_path):
    paths, rig = image_set
    panel = window.intrinsics_panel
    panel.set_board(rig.board)
    panel.add_images(paths)
    with qtbot.waitSignal(panel.intrinsics_changed, timeout=60000):
        panel.calib_btn.click()
    qtbot.waitUntil(lambda: panel.crossval_btn.isEnabled(), timeout=10000)
    for name in ("Residual field", "Residuals per view", "Uncertainty", "Coverage"):
        assert panel.pictures[name].image is not None and not panel.pictures[name].image.isNull(), name
    assert panel.table.cell(9, 0) == "board bow x" and panel.table.cell(10, 0) == "board bow y"
    assert panel.table.cell(9, 3) == "mm"
    with qtbot.waitSignal(panel.crossval_btn.clicked, timeout=1000):
        panel.crossval_btn.click()
    qtbot.waitUntil(lambda: panel.crossval is not None, timeout=60000)
    assert panel.pictures["Cross-validation"].image is not None
    assert panel.message.text().startswith(("consistent", "the model or the data falls short"))
    panel.resize(1000, 800)
    for name, view in panel.pictures.items():
        panel.tabs.setCurrentWidget(view)
        panel.grab().save(str(tmp_path / f"panel-{name.split()[0]}.png"))
    panel.save(tmp_path / "cam.cameramodel")
    assert "LENSMODEL_OPENCV5" in (tmp_path / "cam.cameramodel").read_text()
