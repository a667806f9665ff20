"""pipeline/estimate is the one way from a session to results, for a line and a plane alike (issue 23):
the board's temperature, the input checks, the session lock and the uncertainty budget apply to both."""
from __future__ import annotations

import json
import threading

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.geometry.camera_model import INTRINSIC_NAMES
from lps_gui.errors import InputError
from lps_gui.io.session_lock import SessionBusy, SessionLock
from lps_gui.pipeline.estimate import estimate_session

SOURCES = {"corner noise", "reference view noise", "intrinsics", "board square size", "board temperature",
           "board expansion coefficient", "stage temperature", "Abbe offset"}
SIMULATE = {"line": ["--points", "--preset", "small", "--seed", "3"],
            "planar": ["--points", "--planar", "--preset", "small-planar", "--seed", "5"]}


@pytest.fixture(scope="module", params=sorted(SIMULATE))
def session(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param) / "s"
    assert lps_main(["simulate", str(folder), *SIMULATE[request.param]]) == 0
    return folder


@pytest.fixture(scope="module")
def planar(tmp_path_factory):
    folder = tmp_path_factory.mktemp("planar") / "s"
    assert lps_main(["simulate", str(folder), *SIMULATE["planar"]]) == 0
    return folder


def _edit_meta(folder, **changes):
    meta = json.loads((folder / "session.json").read_text())
    meta.update(changes)
    (folder / "session.json").write_text(json.dumps(meta))


def test_planar_at_30c_moves_both_axis_scales_by_plus_230ppm(planar, tmp_path):
    _edit_meta(planar, environment={"board_temperature_c": 20.0, "board_cte_ppm_per_k": 23.0})
    at20 = estimate_session(planar, out_dir=tmp_path / "at20")
    _edit_meta(planar, environment={"board_temperature_c": 30.0, "board_cte_ppm_per_k": 23.0,
                                    "square_mm_uncertainty_um": 1.0})
    at30 = estimate_session(planar, out_dir=tmp_path / "at30")
    _edit_meta(planar, environment={})
    p20, p30 = at20["figures"]["planar"], at30["figures"]["planar"]
    for axis in ("x", "y"):
        # scale' = (1 + s)(1 + 230e-6) - 1: the board's length unit scales every position
        expected = 230.0 * (1.0 + 1e-6 * p20[f"scale_{axis}_ppm"])
        assert p30[f"scale_{axis}_ppm"] - p20[f"scale_{axis}_ppm"] == pytest.approx(expected, abs=0.01)
    m20 = np.array([[r["measured_x_mm"], r["measured_y_mm"]] for r in at20["positions"]], dtype=float)
    m30 = np.array([[r["measured_x_mm"], r["measured_y_mm"]] for r in at30["positions"]], dtype=float)
    ref = m20[0]
    assert np.allclose(m30 - ref, (m20 - ref) * (1 + 230e-6), rtol=0, atol=1e-6)
    assert at30["environment"]["board_scale_correction_ppm"] == pytest.approx(230.0)
    assert at30["board"]["square_mm"] == at20["board"]["square_mm"]  # nominal kept, the used one recorded
    assert at30["environment"]["square_mm_used"] == pytest.approx(at30["environment"]["square_mm_nominal"] * (1 + 230e-6))


def test_planar_results_carry_the_uncertainty_budget_of_each_axis(planar, tmp_path):
    _edit_meta(planar, environment={"board_temperature_c": 30.0, "board_cte_ppm_per_k": 23.0,
                                    "square_mm_uncertainty_um": 1.0})
    res = estimate_session(planar, out_dir=tmp_path / "unc")
    _edit_meta(planar, environment={})
    per_axis = res["uncertainty"]["per_axis"]
    assert set(per_axis) == {"X", "Y"}
    for name, unc in per_axis.items():
        rows = {r["source"]: r for r in unc["budget"]}
        assert set(rows) == SOURCES  # the line's sources
        travel = max(r[f"target_{name.lower()}_mm"] for r in res["positions"]) - min(
            r[f"target_{name.lower()}_mm"] for r in res["positions"])
        assert unc["travel_mm"] == pytest.approx(travel)
        assert rows["board temperature"]["contribution_um"] > 0
        assert rows["board square size"]["contribution_um"] == pytest.approx(travel / res["board"]["square_mm"])
        assert rows["intrinsics"]["contribution_um"] > 0  # the calibration's covariance propagated to (x, y)
        assert rows["corner noise"]["contribution_um"] > 0
        assert unc["expanded_k2_um"] == pytest.approx(2 * unc["combined_standard_um"]) and unc["expanded_k2_um"] > 0
        assert unc["figures_k2"]["scale_ppm"] > 0
    used = [r for r in res["positions"] if r["used"] and r["sigma_x_um"]]
    assert all(r["sigma_total_x_um"] >= r["sigma_x_um"] and r["sigma_total_y_um"] >= r["sigma_y_um"] for r in used)


def test_an_estimate_is_refused_while_another_writer_holds_the_session(session):
    """Another writer (a capture in another thread) holds the lock: the estimate refuses, writing nothing."""
    held, release = threading.Event(), threading.Event()

    def hold():
        with SessionLock(session, "lps capture --resume S"):
            held.set()
            release.wait(60)

    holder = threading.Thread(target=hold, daemon=True)
    holder.start()
    try:
        assert held.wait(60)
        with pytest.raises(SessionBusy, match="lps capture --resume S"):
            estimate_session(session)
        assert not (session / "results.json").exists()
    finally:
        release.set()
        holder.join(60)


def test_stale_corners_are_refused(session, tmp_path):
    """corners.vnl names the image hash a view was detected in; captures.jsonl lists another now."""
    corners = (session / "corners.vnl").read_text()
    captures = (session / "captures.jsonl").read_text()
    lines = captures.splitlines()
    rec = json.loads(lines[3])
    try:
        head, rest = corners.split("\n", 1)
        (session / "corners.vnl").write_text(f"{head}\n## sha256 {rec['file']} = {'a' * 64}\n{rest}")
        rec["sha256"] = "b" * 64
        lines[3] = json.dumps(rec)
        (session / "captures.jsonl").write_text("\n".join(lines) + "\n")
        with pytest.raises(InputError, match="older image"):
            estimate_session(session, out_dir=tmp_path / "stale")
    finally:
        (session / "corners.vnl").write_text(corners)
        (session / "captures.jsonl").write_text(captures)


def test_views_with_collinear_corners_are_refused(session, tmp_path):
    corners = (session / "corners.vnl").read_text()
    name = json.loads((session / "captures.jsonl").read_text().splitlines()[2])["file"]
    try:
        out = []
        for line in corners.splitlines():
            parts = line.split()
            if len(parts) == 4 and parts[0] == name:  # every corner of this view on the line v = 200
                parts[2] = "200.0"
            out.append(" ".join(parts))
        (session / "corners.vnl").write_text("\n".join(out) + "\n")
        with pytest.raises(InputError, match="on one line"):
            estimate_session(session, out_dir=tmp_path / "collinear")
    finally:
        (session / "corners.vnl").write_text(corners)


def test_planar_self_calibration_through_the_one_path(planar, tmp_path):
    res = estimate_session(planar, options={"self_calibrate": True}, out_dir=tmp_path / "sc")
    assert res["settings"]["self_calibrate"] is True
    estimated = res["parameters"]["intrinsics_estimated"]
    assert list(estimated) == list(INTRINSIC_NAMES) and res["parameters"]["converged"]
    assert estimated["fx"] != res["intrinsics"]["camera_matrix"][0][0]  # free, moved off the prior's centre
