"""Exported poses reproject the board onto the detected corners (issue 12, Must show 3).

The readers here follow the formats' documentation, not our writer: COLMAP's
images.txt holds world-to-camera QW QX QY QZ (Hamilton) and TX TY TZ,
cameras.txt FULL_OPENCV fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6 with the image
corner at 0 (pixel centres at +0.5); nerfstudio's transform_matrix is
camera-to-world with OpenGL camera axes (x right, y up, z back).
"""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import paper_rig_spec
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.pipeline.export import export_session
from lps_gui.sim.points import simulate_point_session


def quat_to_R(w, x, y, z):
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def project(R, t, X, fx, fy, cx, cy, k1, k2, p1, p2, k3):
    """OpenCV's model written out (SPEC 2), in the exported pixel convention."""
    x = X @ R.T + t
    a, b = x[:, 0] / x[:, 2], x[:, 1] / x[:, 2]
    r2 = a * a + b * b
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    xd = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a)
    yd = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b
    return np.stack([fx * xd + cx, fy * yd + cy], axis=1)


def read_colmap(folder):
    cam = [ln.split() for ln in (folder / "cameras.txt").read_text().splitlines() if ln and not ln.startswith("#")][0]
    assert cam[1] == "FULL_OPENCV" and len(cam) == 4 + 12
    params = [float(v) for v in cam[4:]]
    assert params[9:] == [0.0, 0.0, 0.0]
    lines = [ln for ln in (folder / "images.txt").read_text().splitlines() if not ln.startswith("#")]
    poses = {}
    for head, points in zip(lines[0::2], lines[1::2]):
        f = head.split()
        assert points == "" and f[8] == "1"
        q = np.array([float(v) for v in f[1:5]])
        poses[f[9]] = (quat_to_R(*q), np.array([float(v) for v in f[5:8]]))
    pts = np.array([[float(v) for v in ln.split()[1:4]] for ln in (folder / "points3D.txt").read_text().splitlines()
                    if ln and not ln.startswith("#")])
    return params[:9], poses, pts


def read_nerfstudio(folder):
    doc = json.loads((folder / "transforms.json").read_text())
    assert doc["camera_model"] == "OPENCV"
    params = [doc[k] for k in ("fl_x", "fl_y", "cx", "cy", "k1", "k2", "p1", "p2", "k3")]
    poses = {}
    for fr in doc["frames"]:
        M = np.array(fr["transform_matrix"])
        R_c2w = M[:3, :3] @ np.diag([1.0, -1.0, -1.0])  # OpenGL camera axes -> OpenCV
        R = R_c2w.T
        poses[fr["file_path"].split("/", 1)[-1] if not fr["file_path"].startswith("images/") else fr["file_path"]] = (R, -R @ M[:3, 3])
    return params, poses


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("export") / "s"
    plan = Plan(start_mm=0.0, stop_mm=60.0, step_mm=2.0, directions="both", runs=1)
    spec = replace(paper_rig_spec(seed=2, plan=plan), replaced_views=(7,))
    simulate_point_session(spec, folder)
    return folder, estimate_session(folder)


def reprojection_rms(folder, results, params, poses, X):
    table = read_corners_vnl(folder / "corners.vnl", len(X))
    fx, fy, cx, cy, k1, k2, p1, p2, k3 = params
    sq = []
    for name, uv in zip(table.names, table.corners_px):
        key = next((k for k in poses if k.endswith(name)), None)
        if key is None:
            continue
        R, t = poses[key]
        pred = project(R, t, X, fx, fy, cx, cy, k1, k2, p1, p2, k3) - 0.5  # back to OpenCV's pixel centres
        ok = np.isfinite(uv[:, 0])
        sq.append(np.sum((pred[ok] - uv[ok]) ** 2, axis=1))
    return np.sqrt(np.mean(np.concatenate(sq) / 2)), len(sq)  # per coordinate, like the estimate's rms_px


def test_colmap_and_nerfstudio_reproject_the_board(session, tmp_path):
    folder, results = session
    own = results["parameters"]["rms_px"]
    X = None
    res = export_session(folder, "colmap", tmp_path / "colmap")
    params, poses, X = read_colmap(tmp_path / "colmap")
    rms_c, n_c = reprojection_rms(folder, results, params, poses, X)
    res_ns = export_session(folder, "nerfstudio", tmp_path / "ns")
    params_ns, poses_ns = read_nerfstudio(tmp_path / "ns")
    rms_n, n_n = reprojection_rms(folder, results, params_ns, poses_ns, X)
    n_used = results["parameters"]["n_used"]
    assert n_c == n_n == n_used == res.n_exported == res_ns.n_exported
    assert any("000007" in line for line in res.excluded)
    assert "000007" in (tmp_path / "colmap" / "excluded.txt").read_text()
    for rms in (rms_c, rms_n):
        assert rms <= 1.2 * own + 0.02, (rms, own)


def test_csv_has_nominal_and_measured_centres(session, tmp_path):
    folder, results = session
    export_session(folder, "csv", tmp_path / "csv")
    import csv

    rows = list(csv.DictReader((tmp_path / "csv" / "camera_centres.csv").open()))
    assert len(rows) == results["parameters"]["n_used"]
    truth = {r["index"]: r for r in results["positions"]}
    for r in rows[1:5]:
        nom = np.array([float(r[f"nominal_{a}_mm"]) for a in "xyz"])
        mea = np.array([float(r[f"measured_{a}_mm"]) for a in "xyz"])
        dev = truth[int(r["index"])]["deviation_um"]
        assert np.linalg.norm(mea - nom) * 1e3 == pytest.approx(abs(dev), abs=1e-2)


def test_straightness_components_move_the_cameras_only_when_resolved():
    from lps_gui.io.results.sections import Figures
    from lps_gui.pipeline.export import straightness_resolved

    assert straightness_resolved(Figures.from_dict({})) == (False, False)
    figs = {"straightness": {"v1": {"resolved": True}, "v2": {"resolved": False}}}
    assert straightness_resolved(Figures.from_dict(figs)) == (True, False)
