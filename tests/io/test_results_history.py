"""Re-running `lps estimate` keeps every previous result set; a report older than its results says so."""
import json
import os

from lps_gui.cli import main
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.results.history import history, stale_report_message
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


def test_two_estimates_are_both_kept_and_the_latest_is_recorded(tmp_path, capsys):
    folder = tmp_path / "s"
    simulate_point_session(small_spec(seed=2, views=8, directions="+", runs=1), folder)
    # a result set from before the history existed: kept when it is replaced
    first = estimate_session(folder, method="pnp", out_dir=folder)
    (folder / "report.pdf").write_bytes(b"%PDF-1.4 stand-in")
    os.utime(folder / "report.pdf", (1, 1))
    assert main(["estimate", str(folder)]) == 0
    err = capsys.readouterr().err
    assert "report.pdf: older than results.json" in err and "lps report" in err
    assert stale_report_message(folder) is not None
    kept = history(folder)
    assert [h["method"] for h in kept] == ["pnp", "joint"]
    assert [h["latest"] for h in kept] == [False, True]
    assert json.loads((kept[0]["path"] / "results.json").read_text())["created"] == first["created"]
    assert (kept[1]["path"] / "positions.csv").read_text() == (folder / "positions.csv").read_text()
    latest = json.loads((folder / "results" / "latest.json").read_text())
    assert latest["latest"] == kept[1]["name"] and latest["method"] == "joint"
    (folder / "report.pdf").touch()
    assert stale_report_message(folder) is None


def test_a_top_level_set_other_than_the_recorded_latest_is_kept_before_it_is_replaced(tmp_path):
    """keep_previous skips the copy only when results/latest.json's entry holds the same bytes as the top level."""
    folder = tmp_path / "s"
    simulate_point_session(small_spec(seed=2, views=8, directions="+", runs=1), folder)
    estimate_session(folder, method="pnp")  # recorded as the latest
    assert [h["method"] for h in history(folder)] == ["pnp"]
    estimate_session(folder, method="hybrid", out_dir=folder)  # written over the top level, not recorded
    estimate_session(folder, method="joint")
    assert [h["method"] for h in history(folder)] == ["pnp", "hybrid", "joint"]
    estimate_session(folder, method="joint")  # the top level is the recorded latest: nothing copied twice
    assert [h["method"] for h in history(folder)] == ["pnp", "hybrid", "joint", "joint"]


def test_estimate_of_a_session_named_by_a_relative_path(tmp_path, monkeypatch):
    """`lps estimate s` from the session's parent: the history commit works on relative folders too."""
    simulate_point_session(small_spec(seed=2, views=8, directions="+", runs=1), tmp_path / "s")
    monkeypatch.chdir(tmp_path)
    assert main(["estimate", "s"]) == 0
    assert [h["latest"] for h in history("s")] == [True]
    assert (tmp_path / "s" / "results.json").is_file()
