"""A planar (XY) scene session gives a 2-D light field the same way (issue 38)."""
import json

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import small_planar_spec
from lps_gui.core.truth.stage_errors import PlanarErrorModel
from lps_gui.io.lightfield_files import read_hci
from lps_gui.pipeline.demos.lightfield import capture_scene
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.pipeline.lightfield import make_lightfield
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def planar(tmp_path_factory):
    d = tmp_path_factory.mktemp("planar")
    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(30.0, 20.0), step_mm=(10.0, 10.0))
    simulate_point_session(small_planar_spec(seed=1, plan=plan, errors=PlanarErrorModel()), d / "m")
    estimate_session(d / "m")
    capture_scene(d / "s", d / "m", None, lambda *a: None, None)
    return make_lightfield(d / "s", d / "lf")


def test_a_planar_scene_gives_a_grid_of_rectified_views(planar):
    doc = json.loads((planar.out / "lightfield.json").read_text())
    assert doc["axes"] == ["X", "Y"] and planar.grid.shape == (4, 3)
    assert all(len(v["position_mm"]) == 2 and len(v["sigma_um"]) == 2 for v in doc["views"])
    check = planar.check
    for key in ("vertical_disparity_rms_px", "horizontal_disparity_rms_px"):  # within rows, within columns of views
        assert check[key]["after"] <= 0.05 and check[key]["after"] < 0.2 * check[key]["before"]


def test_the_planar_hci_layout_is_row_major_from_the_top_left(planar):
    assert planar.hci is not None
    params, views = read_hci(planar.hci.parent)
    assert (params.num_cams_x, params.num_cams_y) == (4, 3)
    doc = json.loads((planar.out / "lightfield.json").read_text())
    R = np.array(doc["R_cam_board"])
    xy = np.array([[np.array(v["centre_mm"]) @ R[0], np.array(v["centre_mm"]) @ R[1]] for v in doc["views"]])
    order = np.lexsort((np.round(xy[:, 0] / 10.0), np.round(xy[:, 1] / 10.0)))  # rows down the image, left to right
    for n, k in enumerate(order):
        assert views[n].read_bytes() == (planar.out / doc["views"][k]["file"]).read_bytes()
