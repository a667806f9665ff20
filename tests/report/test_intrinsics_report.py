"""The intrinsics report and its pictures, from a calibration of projected corners with one bad corner."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.intrinsics.calibration import calibrate_intrinsics
from lps_gui.core.intrinsics.crossval import cross_validate
from lps_gui.core.truth.simulate import small_spec

INTR = small_spec().rig.intrinsics
BOARD = Board(9, 6, 20.0, warp_mm=(0.3, 0.2))


@pytest.fixture(scope="module")
def corners():
    rng = np.random.default_rng(4)
    out = []
    for k in range(16):
        phi = 2 * np.pi * k / 16
        R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * np.deg2rad(35) * rng.uniform(0.5, 1.0))
        t = np.array([rng.uniform(-40, 40), rng.uniform(-30, 30), 400.0]) - R @ BOARD.centre_mm()
        out.append(project_board(R, t, BOARD.object_points(), INTR) + rng.normal(0, 0.05, (54, 2)))
    out[5][20] += [1.0, 1.0]
    return out


def test_pictures_show_the_data(corners):
    from lps_gui.report.pdf.intrinsics_pictures import PICTURE_PX, intrinsics_pictures

    cal = calibrate_intrinsics(BOARD.flat_points(), corners, INTR.image_size)
    pics = intrinsics_pictures(cal, cross_validate(BOARD.flat_points(), corners, INTR.image_size))
    assert [c for c, _ in pics] == ["Residual vector field", "Per-view residuals", "Projection uncertainty", "Coverage",
                                    "Cross-validation"]
    for caption, img in pics:
        assert (img.width(), img.height()) == PICTURE_PX
        arr = np.frombuffer(img.constBits(), np.uint8).reshape(img.height(), img.width(), 4)
        assert len(np.unique(arr.reshape(-1, 4)[::97], axis=0)) > 5, caption  # not blank
    # the rejected corner is painted red in the residual field
    arr = np.frombuffer(pics[0][1].constBits(), np.uint8).reshape(PICTURE_PX[1], PICTURE_PX[0], 4)
    red = (arr[..., 2] > 180) & (arr[..., 1] < 60) & (arr[..., 0] < 60)
    assert red.sum() > 20


def test_report_pdf(corners, tmp_path):
    from lps_gui.report.pdf.intrinsics import parameter_rows, write_intrinsics_report

    cal = calibrate_intrinsics(BOARD.flat_points(), corners, INTR.image_size)
    assert [(c.view, c.corner) for c in cal.rejected_corners] == [(5, 20)]
    rows = parameter_rows(cal)
    assert rows[9][0] == "board bow x" and rows[10][0] == "board bow y" and rows[9][3] == "mm"
    out = tmp_path / "intrinsics.pdf"
    pages = write_intrinsics_report(cal, out)
    assert pages == 3 and out.read_bytes().startswith(b"%PDF")
    assert not list(tmp_path.glob(".*.tmp"))
    from lps_gui.errors import InputError

    with pytest.raises(InputError, match="folder not found"):
        write_intrinsics_report(cal, tmp_path / "missing" / "x.pdf")


def test_the_intrinsics_pdf_names_its_date_board_and_lens_model(corners, tmp_path):
    """Issue 37: the intrinsics PDF had no date and no board."""
    from pypdf import PdfReader

    from lps_gui.report.pdf.intrinsics import write_intrinsics_report

    cal = calibrate_intrinsics(BOARD.flat_points(), corners, INTR.image_size)
    out = tmp_path / "intrinsics.pdf"
    write_intrinsics_report(cal, out, board=BOARD, date="2026-12-03 10:00:00+0000")
    text = " ".join(PdfReader(out).pages[0].extract_text().split()).replace("\ufb03", "ffi")  # Qt's ligature
    assert "Date 2026-12-03 10:00:00+0000" in text
    assert f"{BOARD.cols}\u00d7{BOARD.rows} inner corners, square {BOARD.square_mm:g} mm" in text
    assert "OpenCV 5 coefficients" in text
