"""`lps capture --report`: the capture ends in results.json and the PDF, equal to a separate detect + estimate."""
from __future__ import annotations

import json
import shutil

import numpy as np

from lps_gui.cli import main as lps_main
def test_capture_report_equals_separate_detect_and_estimate(tmp_path, capsys):
    folder = tmp_path / "s"
    assert lps_main(["capture", "--out", str(folder), "--preset", "small", "--stop", "14", "--report"]) == 0
    out = capsys.readouterr().out
    assert f"results: {folder / 'results.json'}" in out and f"report: {folder / 'report.pdf'}" in out
    assert (folder / "report.pdf").read_bytes().startswith(b"%PDF")
    copy = tmp_path / "copy"  # the same session, detected and estimated the usual way
    shutil.copytree(folder, copy)  # file times kept: corners.vnl's stat comments are the same
    for name in ("corners.vnl", "results.json", "positions.csv", "summary.csv", "report.pdf"):
        (copy / name).unlink()
    shutil.rmtree(copy / "results")
    assert lps_main(["detect", str(copy)]) == 0
    assert lps_main(["estimate", str(copy)]) == 0
    assert (copy / "corners.vnl").read_bytes() == (folder / "corners.vnl").read_bytes()
    live, separate = (json.loads((f / "results.json").read_text()) for f in (folder, copy))
    for key in ("measured_mm", "sigma_um", "rms_px"):
        np.testing.assert_allclose([p[key] for p in live["positions"]], [p[key] for p in separate["positions"]],
                                   rtol=1e-9, atol=0)


def test_live_on_a_resumed_capture_without_frames_left_still_ends_in_results(tmp_path, capsys):
    folder = tmp_path / "s"
    assert lps_main(["capture", "--out", str(folder), "--preset", "small", "--stop", "10"]) == 0
    assert not (folder / "corners.vnl").exists()  # without --live nothing changes
    assert lps_main(["capture", "--resume", str(folder), "--live"]) == 0
    assert (folder / "results.json").exists() and b"## live" not in (folder / "corners.vnl").read_bytes()
