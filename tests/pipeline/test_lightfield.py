"""`lps demo --lightfield --quick` end to end: the light field of a measured stage, checked against the simulator's truth."""
import json

import numpy as np
import pytest

from lps_gui.io.lightfield_files import read_hci


@pytest.fixture
def demo(lightfield_demo):
    return lightfield_demo


def test_without_compensation_the_hci_layout_is_refused_naming_the_largest_deviation(demo):
    plain = demo.plain
    assert plain.hci is None and not (plain.out / "hci").exists()
    assert "HCI layout not written: view" in plain.refusal and "off a uniform grid along X" in plain.refusal
    z = plain.grid.z.max()
    assert z > 2.0 and f"{z:.1f} sigma" in plain.refusal
    doc = json.loads((plain.out / "lightfield.json").read_text())
    assert doc["uniform"]["hci"] is False and doc["uniform"]["refusal"] == plain.refusal


def test_with_compensation_the_hci_layout_is_written_and_read_back(demo):
    lf = demo.compensated
    assert lf.hci is not None and demo.hci_views_equal is True
    params, views = read_hci(lf.hci.parent)
    doc = json.loads((lf.out / "lightfield.json").read_text())
    assert (params.num_cams_x, params.num_cams_y) == (len(doc["views"]), 1)
    assert params.baseline_mm == pytest.approx(lf.grid.spacing_mm[0])
    assert params.focal_px == pytest.approx(doc["virtual_camera"]["camera_matrix"][0][0])
    # row-major from the left: input_Cam000 is the view furthest along -x of the virtual camera
    R = np.array(doc["R_cam_board"])
    along = [np.array(v["centre_mm"]) @ R[0] for v in doc["views"]]
    first = doc["views"][int(np.argmin(along))]["file"]
    assert (lf.out / first).read_bytes() == views[0].read_bytes()


def test_compensated_views_sit_where_the_measurement_says_the_nominal_grid_is(demo):
    """The table's inverse sent every stop where the measured curve crosses the nominal: positions on the grid."""
    doc = json.loads((demo.compensated.out / "lightfield.json").read_text())
    pos = np.array([v["position_mm"][0] for v in doc["views"]])
    nominal = np.array([v["nominal_mm"][0] for v in doc["views"]])
    commanded = np.array([v["commanded_mm"][0] for v in doc["views"]])
    assert np.abs(commanded - nominal).max() > 0.004  # the table moved the commands by micrometres
    assert np.abs(pos - nominal).max() < 0.5e-3
    assert demo.compensated.grid.z.max() < 0.5
    plain = json.loads((demo.plain.out / "lightfield.json").read_text())
    assert all("commanded_mm" not in v for v in plain["views"])


def test_lightfield_json_has_spec_17s_fields(demo):
    doc = json.loads((demo.compensated.out / "lightfield.json").read_text())
    assert doc["format"] == "lps-lightfield/1" and doc["axes"] == ["X"]
    assert doc["measurement_session"]["path"] == str(demo.measurement.resolve())
    assert set(doc["virtual_camera"]) >= {"image_size", "camera_matrix"}
    for v in doc["views"]:
        assert set(v) >= {"file", "index", "position_mm", "sigma_um", "nominal_mm"}
        assert (demo.compensated.out / v["file"]).is_file()
        assert "commanded_mm" in v  # sent through the table
    images = (demo.compensated.out / "colmap" / "images.txt").read_text().splitlines()
    assert len([line for line in images if line and not line.startswith("#")]) == len(doc["views"])
    cams = (demo.compensated.out / "colmap" / "cameras.txt").read_text().splitlines()[-1].split()
    assert cams[1] == "FULL_OPENCV" and all(float(x) == 0.0 for x in cams[8:])  # rectified: no distortion left
    ns = json.loads((demo.compensated.out / "nerfstudio" / "transforms.json").read_text())
    assert len(ns["frames"]) == len(doc["views"]) and ns["k1"] == 0.0


def test_the_epipolar_check_meets_the_issue(demo):
    for lf in (demo.plain, demo.compensated):
        check = lf.check
        v = check["vertical_disparity_rms_px"]
        assert v["after"] <= 0.05 and v["after"] < 0.2 * v["before"]
        planes = check["disparity_vs_position"]
        assert len(planes) == 3
        for p in planes:
            assert p["residual_rms_px_measured"] <= 0.05
            assert p["depth_from_slope_mm_measured"] == pytest.approx(p["depth_mm"], rel=0.01)


def test_the_report_page_shows_the_epis_and_the_numbers(demo, tmp_path):
    from pypdf import PdfReader

    from lps_gui.report.pdf.lightfield import write_lightfield_report

    path = demo.compensated.out / "report.pdf"
    text = " ".join(PdfReader(str(path)).pages[0].extract_text().split())
    assert "vertical disparity RMS, after" in text.replace("\t", " ") or "vertical\tdisparity" in text
    doc = json.loads((demo.compensated.out / "lightfield.json").read_text())
    import cv2

    before = cv2.imread(str(demo.compensated.out / "epi_before.png"), cv2.IMREAD_GRAYSCALE)
    after = cv2.imread(str(demo.compensated.out / "epi_after.png"), cv2.IMREAD_GRAYSCALE)
    assert before.shape == after.shape and before.shape[0] >= 240
    clipped: list = []
    assert write_lightfield_report(doc, before, after, tmp_path / "r.pdf", clipped) >= 1
    assert clipped == []
