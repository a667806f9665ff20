"""The HCI 4D light field benchmark layout, written and read back by a reader of the format's description."""
import configparser

import numpy as np
import pytest

from lps_gui.errors import InputError
from lps_gui.io.lightfield_files import HCI_VIEW, read_hci, write_hci_parameters, write_png


def _write(folder, shape=(5, 1)):
    folder.mkdir(parents=True, exist_ok=True)
    path = write_hci_parameters(folder, image_size=(64, 48), focal_px=600.0, pixel_mm=0.00586, shape=shape,
                                baseline_mm=2.0001, centre_m=np.array([0.01, 0.02, -0.5]),
                                rotation_rad=np.array([0.001, 0.002, 0.003]), scene="s", date="2026-12-03",
                                version="0", disparity=None)
    for k in range(shape[0] * shape[1]):
        write_png(folder / HCI_VIEW.format(k), np.full((48, 64), k, np.uint8))
    return path


def test_parameters_cfg_holds_every_key_of_the_description(tmp_path):
    path = _write(tmp_path / "hci")
    cfg = configparser.ConfigParser()
    cfg.read(path)
    keys = {"intrinsics": {"image_resolution_x_px", "image_resolution_y_px", "focal_length_mm", "sensor_size_mm", "fstop"},
            "extrinsics": {"num_cams_x", "num_cams_y", "baseline_mm", "focus_distance_m", "center_cam_x_m",
                           "center_cam_y_m", "center_cam_z_m", "center_cam_rx_rad", "center_cam_ry_rad",
                           "center_cam_rz_rad"},
            "meta": {"disp_min", "disp_max", "frustum_disp_min", "frustum_disp_max", "depth_map_scale", "scene",
                     "category", "date", "version", "authors", "contact"}}
    for section, names in keys.items():
        assert set(cfg[section]) == names
    params, views = read_hci(tmp_path / "hci")
    assert (params.width, params.height, params.num_cams_x, params.num_cams_y) == (64, 48, 5, 1)
    assert params.focal_px == pytest.approx(600.0)  # focal_length_mm / sensor_size_mm * max(w, h)
    assert params.baseline_mm == 2.0001 and params.focus_distance_m == float("inf")
    assert [v.name for v in views] == [f"input_Cam{k:03d}.png" for k in range(5)]


def test_read_hci_names_a_missing_view_and_a_broken_file(tmp_path):
    _write(tmp_path / "hci", (2, 2))
    (tmp_path / "hci" / "input_Cam002.png").unlink()
    with pytest.raises(InputError, match="input_Cam002.png is missing"):
        read_hci(tmp_path / "hci")
    (tmp_path / "hci" / "parameters.cfg").write_text("[intrinsics]\nimage_resolution_x_px = 4\n")
    with pytest.raises(InputError, match="not an HCI parameters file"):
        read_hci(tmp_path / "hci")
