"""Intrinsics from a rendered varied-pose set recover the truth within 3 reported std."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.camera_model import INTRINSIC_NAMES
from lps_gui.core.simulate import small_spec
from lps_gui.io.intrinsics_file import read_intrinsics
from lps_gui.pipeline.intrinsics import calibrate_images
from lps_gui.sim.images import simulate_intrinsics_set

SPEC = small_spec()


@pytest.fixture(scope="module")
def image_set(tmp_path_factory):
    folder = tmp_path_factory.mktemp("intrinsics-set")
    paths = simulate_intrinsics_set(folder, SPEC.rig.board, SPEC.rig.intrinsics, n_views=20, seed=1)
    return folder, paths


def test_rendered_set_recovers_truth_within_3_std(image_set):
    _, paths = image_set
    cal = calibrate_images(paths, SPEC.rig.board, workers=1)
    z = (cal.intrinsics.vector() - SPEC.rig.intrinsics.vector()) / cal.std
    assert np.all(np.abs(z) < 3.0), dict(zip(INTRINSIC_NAMES, z))
    assert cal.rms_px < 0.06 and not cal.flagged_views
    assert cal.intrinsics.std() is not None and np.allclose(cal.intrinsics.std(), cal.std)
    assert cal.intrinsics.extra["per_view_rms_px"][str(paths[0])] > 0


def test_cli_writes_json_and_yaml_and_reports_a_broken_image(image_set, tmp_path, capsys):
    folder, paths = image_set
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"\x89PNG garbage")
    out, yaml = tmp_path / "intr.json", tmp_path / "intr.yaml"
    code = lps_main(["intrinsics", str(folder), str(broken), "--board", str(folder / "board.json"),
                     "--out", str(out), "--yaml", str(yaml), "--workers", "1"])
    assert code == 3
    text = capsys.readouterr()
    assert "broken.png" in text.out and " fx =" in text.out
    j, y = read_intrinsics(out), read_intrinsics(yaml)
    assert np.allclose(j.vector(), y.vector()) and np.allclose(j.std(), y.std())
    assert abs(j.fx - SPEC.rig.intrinsics.fx) < 3 * j.std()[0]
    assert any("broken.png" in w for w in j.extra["warnings"])
