"""`lps estimate` on session folders: results files, truth, and every bad input of issue 3."""
import json
from dataclasses import replace

import pytest

from lps_gui.cli import main
from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.results.model import read_results
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


@pytest.fixture()
def session(tmp_path):
    spec = replace(small_spec(seed=3, views=12, directions="both", runs=2), replaced_views=(4,))
    simulate_point_session(spec, tmp_path / "s")
    return tmp_path / "s"


def test_results_files_follow_spec(session):
    results = estimate_session(session)
    assert (session / "positions.csv").exists() and (session / "summary.csv").exists()
    assert read_results(session).to_dict() == json.loads(json.dumps(results))
    header = (session / "positions.csv").read_text().splitlines()[0].split(",")
    assert header == ["index", "run", "direction", "target_mm", "measured_mm", "deviation_um", "sigma_um", "rms_px",
                      "outlier", "straightness_um_1", "straightness_um_2", "roll_urad", "pitch_urad", "yaw_urad",
                      "eax_urad", "ebx_urad", "ecx_urad", "eax_sigma_urad", "ebx_sigma_urad", "ecx_sigma_urad"]  # SPEC 14
    assert len(results["positions"]) == 48
    assert results["figures"]["iso230_2"] is not None  # 2 runs in both directions
    tc = results["truth_comparison"]
    assert tc["flagged_outliers"] == tc["injected_outliers"] == [4]
    # errors against truth are of the size of the reported sigmas
    assert tc["position_rms_error_um"] < 3 * tc["mean_sigma_um"]


def test_inputs_record_the_hash_of_every_file_read(session):
    """corners.vnl is hashed as it is parsed, the others from disk: all equal the files' own sha256."""
    from lps_gui.io.atomic import sha256_file
    from lps_gui.pipeline.session_checks import stale_inputs

    results = estimate_session(session)
    recorded = results["inputs"]["sha256"]
    assert set(recorded) == {"session.json", "captures.jsonl", "corners.vnl"}
    assert all(recorded[name] == sha256_file(session / name) for name in recorded)
    assert stale_inputs(session, results) == []


def test_truth_comparison_is_the_positions_table_against_its_truth_column(session):
    """One reference: deviation_um and truth_deviation_um are both zero at the reference capture, so the
    figure recomputed from the table equals truth_comparison's."""
    import numpy as np

    results = estimate_session(session)
    rows = [r for r in results["positions"] if r["used"]]
    ref = results["parameters"]["reference_index"]
    ref_row = next(r for r in results["positions"] if r["index"] == ref)
    assert ref_row["deviation_um"] == 0.0 and ref_row["truth_deviation_um"] == 0.0
    err = np.array([r["deviation_um"] - r["truth_deviation_um"] for r in rows])
    tc = results["truth_comparison"]
    assert tc["position_rms_error_um"] == pytest.approx(np.sqrt(np.mean(err**2)), rel=1e-9)
    assert tc["position_max_abs_error_um"] == pytest.approx(np.max(np.abs(err)), rel=1e-9)
    # the sigma the bands draw (sigma_total_um: noise and the intrinsics), also the z test's (issue 35)
    assert tc["median_sigma_um"] == pytest.approx(np.median([r["sigma_total_um"] for r in rows]))
    others = [r for r in rows if r["index"] != ref]
    z2 = np.mean([((r["deviation_um"] - r["truth_deviation_um"]) / r["sigma_total_um"]) ** 2 for r in others])
    assert tc["z_mean_square"] == pytest.approx(z2, rel=1e-6)


@pytest.mark.parametrize("method", ["hybrid", "pnp"])
def test_other_methods_write_results(session, tmp_path, method):
    results = estimate_session(session, method=method, out_dir=tmp_path / method)
    assert results["method"] == method
    assert (tmp_path / method / "results.json").exists()


def run_cli(*args):
    return main(["estimate", *map(str, args)])


def assert_fails_cleanly(session, capsys, *needles):
    before = sorted(p.name for p in session.iterdir())
    assert run_cli(session) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err  # one line, no traceback
    for needle in needles:
        assert needle in err
    assert sorted(p.name for p in session.iterdir()) == before  # nothing written
    assert not (session / "results.json").exists()


def test_empty_corners_file(session, capsys):
    (session / "corners.vnl").write_text("")
    assert_fails_cleanly(session, capsys, "corners.vnl", "lps detect")


def test_truncated_corners_file(session, capsys):
    text = (session / "corners.vnl").read_text()
    (session / "corners.vnl").write_text(text[: len(text) // 2])
    assert_fails_cleanly(session, capsys, "corners.vnl")


def test_session_without_intrinsics(session, capsys):
    meta = json.loads((session / "session.json").read_text())
    meta["intrinsics"] = None
    (session / "session.json").write_text(json.dumps(meta))
    assert_fails_cleanly(session, capsys, "intrinsics", "lps intrinsics")


def keep_captures(session, predicate):
    lines = (session / "captures.jsonl").read_text().splitlines()
    (session / "captures.jsonl").write_text("\n".join(l for l in lines if predicate(json.loads(l))) + "\n")


def test_fewer_than_three_views(session, capsys):
    keep_captures(session, lambda r: r["index"] < 2)
    assert_fails_cleanly(session, capsys, "at least 3")


def test_all_views_at_one_position(session, capsys):
    keep_captures(session, lambda r: r["target_mm"] == 0.0)
    assert_fails_cleanly(session, capsys, "one target position")


def test_board_size_mismatch(session, capsys):
    meta = json.loads((session / "session.json").read_text())
    meta["board"]["inner_corners"] = [10, 6]
    (session / "session.json").write_text(json.dumps(meta))
    assert_fails_cleanly(session, capsys, "corners.vnl", "inner_corners")


def test_nan_in_corners(session, capsys):
    lines = (session / "corners.vnl").read_text().splitlines()
    name, x, y, level = lines[5].split()
    lines[5] = f"{name} nan {y} {level}"
    (session / "corners.vnl").write_text("\n".join(lines) + "\n")
    assert_fails_cleanly(session, capsys, "corners.vnl", "NaN")


def test_previous_results_survive_a_failed_run(session, capsys):
    estimate_session(session)
    good = (session / "results.json").read_text()
    (session / "corners.vnl").write_text("")
    assert run_cli(session) == 2
    assert (session / "results.json").read_text() == good


def test_cli_prints_summary_with_truth(session, capsys):
    assert run_cli(session) == 0
    out = capsys.readouterr().out
    assert "against truth" in out and "outlier view 4" in out
