"""mrcal .cameramodel read and write: round trips, and a file written by hand from mrcal's documented format."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.errors import InputError
from lps_gui.io.cameramodel_file import format_cameramodel, parse_cameramodel, read_cameramodel, write_cameramodel
from lps_gui.io.intrinsics_file import read_intrinsics, write_intrinsics

INTR = replace(
    CameraIntrinsics.from_values((1280, 960), 1210.5, 1209.75, 641.25, 478.5, dist=(-0.21, 0.11, 4e-4, -3e-4, -0.02),
                                 std=np.array([0.5, 0.5, 0.3, 0.3, 1e-3, 2e-3, 1e-5, 1e-5, 3e-3])),
    rms_px=0.12, n_views=25, extra={"board_warp_mm": [0.4, -0.1], "board_warp_sigma_mm": [0.02, 0.02]},
)

# as the mrcal docs show a .cameramodel (comments, trailing commas, an optional region and binary inputs)
HAND_WRITTEN_OPENCV8 = """# generated on 2020-11-14 21:49:59 with mrcal-calibrate-cameras
{
    'lensmodel':  'LENSMODEL_OPENCV8',

    # intrinsics are fx,fy,cx,cy,distortion0,distortion1,....
    'intrinsics': [ 2073.872915, 2077.452267, 3004.686823, 1997.377253, -0.2791613797, 0.0866824914, 4.398264387e-05, -1.180073913e-05, -0.01959722542, 0, 0, 0,],

    'valid_intrinsics_region': [
    [ 622, 0 ],
    [ 0, 634 ],
    [ 622, 0 ],
],

    # extrinsics are rt_fromref
    'extrinsics': [ 0, 0, 0, 0, 0, 0,],

    'imagersize': [ 6016, 4016,],

    'icam_intrinsics': 0,

    'optimization_inputs': b'P)h>@6aWAK2mk;8AprP8D',
}
"""


def test_reads_a_hand_written_opencv8_model():
    intr = parse_cameramodel(HAND_WRITTEN_OPENCV8)
    assert intr.image_size == (6016, 4016)
    assert (intr.fx, intr.fy, intr.cx, intr.cy) == (2073.872915, 2077.452267, 3004.686823, 1997.377253)
    assert np.array_equal(intr.dist, [-0.2791613797, 0.0866824914, 4.398264387e-05, -1.180073913e-05, -0.01959722542])


def test_reads_a_hand_written_opencv5_and_pinhole_model():
    text = "{'lensmodel': 'LENSMODEL_OPENCV5', 'intrinsics': [500, 501, 320, 240, -0.1, 0.01, 0.001, 0.002, 0.0003],\n" \
           " 'extrinsics': [0,0,0,0,0,0], 'imagersize': [640, 480]}"
    intr = parse_cameramodel(text)
    assert np.array_equal(intr.vector(), [500, 501, 320, 240, -0.1, 0.01, 0.001, 0.002, 0.0003])
    pin = parse_cameramodel("{'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': [500, 500, 320, 240], 'imagersize': [640, 480]}")
    assert np.array_equal(pin.dist, np.zeros(5))


@pytest.mark.parametrize("lensmodel", ["LENSMODEL_OPENCV5", "LENSMODEL_OPENCV8"])
def test_round_trip(tmp_path, lensmodel):
    path = tmp_path / "cam.cameramodel"
    write_cameramodel(path, INTR, lensmodel)
    back = read_cameramodel(path)
    assert np.array_equal(back.vector(), INTR.vector()) and back.image_size == INTR.image_size
    text = path.read_text()
    assert f"'lensmodel':  '{lensmodel}'" in text and "'extrinsics': [ 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,]" in text
    assert "# board warp (mrcal calobject_warp) 0.4 +- 0.02" in text
    n = 12 if lensmodel.endswith("8") else 9
    import ast

    assert len(ast.literal_eval(text)["intrinsics"]) == n


def test_by_suffix_beside_json_and_yaml(tmp_path):
    for name in ("cam.cameramodel", "cam.json", "cam.yaml"):
        write_intrinsics(tmp_path / name, INTR)
        assert np.allclose(read_intrinsics(tmp_path / name).vector(), INTR.vector(), rtol=0, atol=1e-12)
    assert read_intrinsics(tmp_path / "cam.cameramodel").std() is None  # mrcal keeps no std; our comments are not data
    assert format_cameramodel(read_intrinsics(tmp_path / "cam.cameramodel")).count("{") == 1


@pytest.mark.parametrize("text, message", [
    ("{'lensmodel': 'LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100', 'intrinsics': [1,1,1,1], "
     "'imagersize': [1, 1]}", "not supported; convert it with mrcal-convert-lensmodel"),
    ("{'lensmodel': 'LENSMODEL_OPENCV5', 'intrinsics': [500, 500, 320, 240], 'imagersize': [640, 480]}", "needs 9 intrinsics"),
    ("{'lensmodel': 'LENSMODEL_OPENCV5', 'intrinsics': [500, 500, 320, 240, 0, 0, 0, 0, 0]}", "lacks imagersize"),
    ("import os", "not an mrcal .cameramodel"),
])
def test_bad_files_get_one_line_errors(text, message):
    with pytest.raises(InputError, match=message) as err:
        parse_cameramodel(text, "x.cameramodel")
    assert "\n" not in str(err.value)


def test_rational_and_thin_prism_lens_round_trips_through_every_format(tmp_path):
    """A 12-coefficient lens (SPEC 15's lens models) is carried by intrinsics.json, YAML and .cameramodel."""
    from lps_gui.core.geometry.camera_model import CameraIntrinsics

    d = (-0.1, 0.05, 1e-3, -1e-3, 0.01, 0.02, -0.01, 0.005, 1e-3, -2e-3, 3e-3, -4e-4)
    intr = CameraIntrinsics.from_values((640, 480), 600.0, 601.0, 320.0, 240.0, dist=d)
    for name in ("cam.json", "cam.yaml", "cam.cameramodel"):
        write_intrinsics(tmp_path / name, intr)
        back = read_intrinsics(tmp_path / name)
        assert np.allclose(back.cv_dist, d, rtol=0, atol=1e-12), name
    assert "LENSMODEL_OPENCV12" in (tmp_path / "cam.cameramodel").read_text()
    rational = parse_cameramodel("{'lensmodel': 'LENSMODEL_OPENCV8', 'intrinsics': [500, 500, 320, 240, 0, 0, 0, 0, 0, "
                                 "0.5, 0, 0], 'imagersize': [640, 480]}")
    assert np.allclose(rational.higher, [0.5, 0, 0, 0, 0, 0, 0])
