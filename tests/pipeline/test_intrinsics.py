"""Intrinsics from a rendered varied-pose set recover the truth within 3 reported std."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
from lps_gui.core.truth.simulate import small_spec
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


def test_cli_json_carries_the_board_warp_and_the_yaml_is_unchanged(image_set, tmp_path, capsys):
    folder, _ = image_set
    out, yaml = tmp_path / "intr.json", tmp_path / "intr.yaml"
    code = lps_main(["intrinsics", str(folder), "--board", str(folder / "board.json"), "--out", str(out),
                     "--yaml", str(yaml), "--workers", "1", "--cross-validate",
                     "--cameramodel", str(tmp_path / "cam.cameramodel"), "--lensmodel", "opencv8",
                     "--report", str(tmp_path / "intr.pdf")])
    assert code == 0
    assert (tmp_path / "intr.pdf").read_bytes().startswith(b"%PDF")
    assert np.allclose(read_intrinsics(tmp_path / "cam.cameramodel").vector(), read_intrinsics(out).vector())
    assert "LENSMODEL_OPENCV8" in (tmp_path / "cam.cameramodel").read_text()
    text = capsys.readouterr().out
    assert "board bow =" in text and "cross-validation: 10 even views against 10 odd views" in text
    assert "\nconsistent: the two halves differ by" in text
    from lps_gui.io.jsonfile import read_json

    d = read_json(out, "intrinsics")
    bow, sigma = np.array(d["board_warp_mm"]), np.array(d["board_warp_sigma_mm"])
    assert bow.shape == (2,) and sigma.shape == (2,) and np.all(sigma > 0)
    assert np.all(np.abs(bow / sigma) < 3)  # the simulated board is flat
    assert d["rejected_corners"] == []
    nodes = [line.split(":")[0] for line in yaml.read_text().splitlines()[2:] if line and not line.startswith(" ")]
    assert nodes == ["image_width", "image_height", "camera_matrix", "distortion_coefficients", "std_intrinsics", "rms_px"]


def test_the_lps_estimate_uses_the_bowed_board(image_set):
    from dataclasses import replace

    from lps_gui.io.intrinsics_file import apply_board_warp, intrinsics_from_dict, intrinsics_to_dict

    intr = replace(SPEC.rig.intrinsics, extra={"board_warp_mm": [0.6, 0.4], "board_warp_sigma_mm": [0.01, 0.01]})
    back = intrinsics_from_dict(intrinsics_to_dict(intr))
    board = apply_board_warp(SPEC.rig.board, back)
    assert board.warp_mm == (0.6, 0.4)
    X = board.object_points()
    assert X[:, 2].max() == pytest.approx(0.6 + 0.4 * (1 - 0.2**2))  # centre column; rows 2 and 3 sit at y = -+0.2
    assert np.allclose(X[[0, 8, 45, 53], 2], 0.0) and np.allclose(X[:, :2], SPEC.rig.board.flat_points()[:, :2])
    assert apply_board_warp(SPEC.rig.board, SPEC.rig.intrinsics) is SPEC.rig.board
