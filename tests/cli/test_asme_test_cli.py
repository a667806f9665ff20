"""`--test min-step|settling` on lps simulate and lps capture: the plan presets, session.json asme_test, the
results.json section and the report page."""
from __future__ import annotations

import json

import pytest

from lps_gui.cli import main as lps_main
from lps_gui.io.session import Session


def test_simulate_min_step_with_a_dead_band_estimates_a_sticking_stage(tmp_path, capsys):
    out = tmp_path / "s"
    assert lps_main(["simulate", str(out), "--points", "--test", "min-step", "--test-steps", "4", "--dead-band-um", "3",
                     "--spec", "paper,min_step=2"]) == 0
    session = Session.open(out)
    assert session.meta["asme_test"] == {"test": "min-step", "step_um": 2.0}
    assert session.meta["stage_spec"]["min_incremental_motion_um"] == 2.0
    plan = session.plan()
    assert plan.frames_per_stop == 8 and plan.directions == "both" and len(plan.targets()) == 15
    capsys.readouterr()
    assert lps_main(["estimate", str(out.resolve())]) == 0
    assert "ASME B5.64: The stage sticks" in capsys.readouterr().out
    section = json.loads((out / "results.json").read_text())["asme_b5_64"]
    assert section["incremental_step"]["sticks"] and section["incremental_step"]["truth"]["dead_band_um"] == 3.0
    assert "Minimum incremental motion" in [r["figure"] for r in section["test_uncertainty_ratio"]]
    from lps_gui.report.pdf.document import render_report

    info = render_report(out.resolve())
    page = next(p for p in info.pages if "ASME B5.64 incremental-step test (minimum incremental motion)" in p)
    assert page[1:] == ["figure:min_step", "Test uncertainty ratio", "ISO 230-2 and ASME B5.64 names"]
    assert not info.clipped
    texts = " ".join(t.text for t in info.texts)
    assert "The stage sticks" in texts and "TUR" in texts


@pytest.mark.parametrize("argv, message", [
    (["--test", "min-step", "--planar"], "single-axis"),
    (["--test", "settling", "--ringing", "50,8"], "AMP_UM,FREQ_HZ,DECAY_S"),
    (["--test", "min-step", "--test-steps", "100000"], "--test-steps"),
])
def test_bad_test_switches_are_one_line_errors(tmp_path, capsys, argv, message):
    try:
        code = lps_main(["simulate", str(tmp_path / "s"), "--points", *argv])
    except SystemExit as exc:  # argparse's own switch errors
        code = exc.code
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "s").exists()


@pytest.mark.slow
def test_capture_settling_on_the_ringing_simulated_rig(tmp_path):
    """Rendered frames through the engine (frame times on its clock) to the settling page: within 20 % of the truth."""
    out = (tmp_path / "c").resolve()
    assert lps_main(["capture", "--out", str(out), "--test", "settling", "--start", "0", "--stop", "40",
                     "--ringing", "150,8,0.25", "--test-band-um", "30", "--frames", "50", "--spec", "settling=1"]) == 0
    assert lps_main(["detect", str(out)]) == 0
    assert lps_main(["estimate", str(out)]) == 0
    settle = json.loads((out / "results.json").read_text())["asme_b5_64"]["settling"]
    assert abs(settle["settling_time_s"] / settle["truth"]["settling_time_s"] - 1.0) < 0.2
    from lps_gui.report.pdf.document import render_report

    info = render_report(out)
    assert any("ASME B5.64 settling test" in page for page in info.pages) and not info.clipped


@pytest.mark.slow
def test_demo_settling_prints_the_settling_time_against_the_truth(tmp_path, capsys):
    assert lps_main(["demo", "--test", "settling", "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "settling time within \u00b15.00 \u00b5m" in out and "true 0.568 s" in out and "TUR Settling time" in out
    assert (tmp_path / "d" / "session" / "report.pdf").is_file()
