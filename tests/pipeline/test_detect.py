"""Session detection against the renderer's truth, re-runs, bad inputs, cancel, and `lps detect`."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.progress import CancelToken
from lps_gui.core.truth.simulate import small_spec, true_views
from lps_gui.errors import Cancelled, InputError
from lps_gui.io.board_file import write_board
from lps_gui.io.corners.vnl import read_corners_vnl
from lps_gui.io.session import Session
from lps_gui.pipeline import detect as detect_mod
from lps_gui.pipeline.detect import detect_images, detect_session
from lps_gui.sim.images import simulate_image_session

SPEC = small_spec(views=12)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rendered") / "session"
    simulate_image_session(SPEC, folder, workers=1)
    _, R, t, _ = true_views(SPEC, np.random.default_rng(SPEC.seed))
    truth = project_board(R, t, SPEC.rig.board.object_points(), SPEC.rig.intrinsics)
    return folder, truth


@pytest.fixture
def session(rendered, tmp_path):
    folder = tmp_path / "session"
    shutil.copytree(rendered[0], folder)
    return folder, rendered[1]


def rms(a, b):
    return float(np.sqrt(np.nanmean(np.sum((a - b) ** 2, axis=-1))))


def test_session_corners_match_truth_and_file_names(session):
    folder, truth = session
    table = detect_session(folder, workers=1)
    names = [r.file for r in Session.open(folder).records()]
    assert table.names == names and not table.failed
    assert rms(table.corners_px, truth) < 0.05
    again = read_corners_vnl(folder / "corners.vnl", SPEC.rig.board.n_corners)
    assert again.names == names
    assert np.allclose(again.corners_px, table.corners_px, atol=1e-4)


def test_parallel_workers_give_the_same_corners(session):
    folder, truth = session
    one = detect_images([folder / f"images/{k:06d}.png" for k in range(12)], SPEC.rig.board, workers=1)
    two = detect_images([folder / f"images/{k:06d}.png" for k in range(12)], SPEC.rig.board, workers=2)
    assert rms(two.corners_px, truth) < 0.05
    assert np.allclose(one.corners_px, two.corners_px, atol=0.02)


def test_rerun_detects_only_new_views(session, monkeypatch):
    folder, _ = session
    detect_session(folder, workers=1)
    calls = []
    real = detect_mod.run_detection
    monkeypatch.setattr(detect_mod, "run_detection", lambda jobs, *a, **k: calls.append([j.name for j in jobs]) or real(jobs, *a, **k))
    detect_session(folder, workers=1)
    assert calls == []  # captures.jsonl unchanged: nothing to do
    s = Session.open(folder)
    last = s.records()[-1]
    shutil.copy(folder / last.file, folder / "images/extra.png")
    s.append(last.__class__(**{**last.__dict__, "index": 99, "file": "images/extra.png"}))
    table = detect_session(folder, workers=1)
    assert calls == [["images/extra.png"]]
    assert "images/extra.png" in table.names and not table.failed


def _spy(monkeypatch) -> list[list[str]]:
    calls: list[list[str]] = []
    real = detect_mod.run_detection
    monkeypatch.setattr(detect_mod, "run_detection", lambda jobs, *a, **k: calls.append([j.name for j in jobs]) or real(jobs, *a, **k))
    return calls


def test_a_replaced_image_is_detected_again_without_force(session, monkeypatch, capsys):
    folder, truth = session
    detect_session(folder, workers=1)
    recs = Session.open(folder).records()
    calls = _spy(monkeypatch)
    shutil.copy(folder / recs[4].file, folder / recs[3].file)  # captures.jsonl unchanged, the image is not
    assert lps_main(["detect", str(folder)]) == 3
    assert calls == [[recs[3].file]]  # only the replaced view
    assert "up to date" not in capsys.readouterr().out
    table = read_corners_vnl(folder / "corners.vnl", SPEC.rig.board.n_corners)
    assert "sha256" in table.failed[recs[3].file]  # the image differs from captures.jsonl: no corners from it
    assert not np.isfinite(table.corners_px[3]).any()
    ok = [i for i in range(12) if i != 3]
    assert rms(table.corners_px[ok], truth[ok]) < 0.05


def test_a_touched_image_with_the_same_bytes_keeps_its_corners(session, monkeypatch):
    import os

    folder, _ = session
    detect_session(folder, workers=1)
    recs = Session.open(folder).records()
    st = os.stat(folder / recs[2].file)
    os.utime(folder / recs[2].file, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    calls = _spy(monkeypatch)
    assert detect_session(folder, workers=1).meta.get("up_to_date") == "yes"  # hashed: the same image
    assert calls == []


def test_corners_without_stat_lines_are_checked_by_hash(session, monkeypatch):
    folder, _ = session
    detect_session(folder, workers=1)
    path = folder / "corners.vnl"
    path.write_text("".join(ln for ln in path.read_text().splitlines(True) if not ln.startswith("## stat ")))
    recs = Session.open(folder).records()
    calls = _spy(monkeypatch)
    assert detect_session(folder, workers=1).meta.get("up_to_date") == "yes"  # an older corners.vnl: hashes agree
    shutil.copy(folder / recs[1].file, folder / recs[6].file)
    detect_session(folder, workers=1)
    assert calls == [[recs[6].file]]


def test_bad_images_are_listed_with_reasons_and_the_run_goes_on(session, capsys):
    folder, truth = session
    recs = Session.open(folder).records()
    (folder / recs[2].file).unlink()  # missing
    data = (folder / recs[5].file).read_bytes()
    (folder / recs[5].file).write_bytes(data[: len(data) // 3])  # truncated
    (folder / recs[7].file).write_bytes(b"not an image")  # unreadable
    table = detect_session(folder, workers=1)
    assert set(table.failed) == {recs[2].file, recs[5].file, recs[7].file}
    assert "missing" in table.failed[recs[2].file]
    assert "sha256" in table.failed[recs[5].file]  # changed since capture
    ok = [i for i in range(12) if i not in (2, 5, 7)]
    assert rms(table.corners_px[ok], truth[ok]) < 0.05
    assert lps_main(["detect", str(folder)]) == 3
    err = capsys.readouterr().err
    assert recs[2].file in err and "missing" in err


def test_unreadable_image_without_hash(tmp_path, rendered):
    folder, truth = rendered
    good = tmp_path / "good.png"
    shutil.copy(folder / "images/000000.png", good)
    bad = tmp_path / "bad.png"
    bad.write_bytes((folder / "images/000001.png").read_bytes()[:5000])
    table = detect_images([good, bad, tmp_path / "nope.png"], SPEC.rig.board, workers=1)
    assert table.failed[str(bad)].startswith("a damaged PNG (its IDAT chunk at byte ")  # found before libpng decodes
    assert table.failed[str(bad)].endswith(" runs past the end of the file: truncated); copy or capture the image again")
    assert table.failed[str(tmp_path / "nope.png")] == "image file missing"
    assert rms(table.corners_px[0], truth[0]) < 0.05


def test_wrong_board_size_fails_every_view_with_a_hint(session):
    folder, _ = session
    meta = json.loads((folder / "session.json").read_text())
    meta["board"]["inner_corners"] = [8, 6]
    (folder / "session.json").write_text(json.dumps(meta))
    table = detect_session(folder, workers=1)
    assert len(table.failed) == 12
    assert all("9x6" in r and "board.json" in r for r in table.failed.values())


def test_cancel_keeps_finished_views(session):
    folder, _ = session
    token = CancelToken()
    seen = []

    def progress(done, total, msg=""):
        seen.append(done)
        if done >= 8:
            token.cancel()

    with pytest.raises(Cancelled):
        detect_session(folder, progress, token, workers=1)
    partial = read_corners_vnl(folder / "corners.vnl", SPEC.rig.board.n_corners)
    assert 8 <= len(partial.names) < 12
    table = detect_session(folder, workers=1)  # resumes: completes the rest
    assert len(table.names) == 12 and not table.failed


def test_detect_images_cli_needs_a_board(session, tmp_path, capsys):
    folder, _ = session
    assert lps_main(["detect", str(folder / "images/000000.png")]) == 2
    assert "--board" in capsys.readouterr().err
    write_board(tmp_path / "board.json", SPEC.rig.board)
    out = tmp_path / "c.vnl"
    code = lps_main(["detect", str(folder / "images"), "--board", str(tmp_path / "board.json"), "--out", str(out), "--workers", "1"])
    assert code == 0
    assert len(read_corners_vnl(out, SPEC.rig.board.n_corners).names) == 12


def test_no_images_is_an_input_error():
    with pytest.raises(InputError):
        detect_images([], SPEC.rig.board)


def test_tracking_survives_replaced_and_bumped_views_and_reversals(tmp_path):
    from dataclasses import replace

    spec = replace(small_spec(views=8, directions="both"), replaced_views=(4,), replaced_offset=6, bumped_views=(10,))
    simulate_image_session(spec, tmp_path / "s", workers=1)
    table = detect_session(tmp_path / "s", workers=1)
    _, R, t, _ = true_views(spec, np.random.default_rng(spec.seed))
    truth = project_board(R, t, spec.rig.board.object_points(), spec.rig.intrinsics)
    shown = np.arange(16)
    shown[4] = 10  # view 4 holds view 10's image
    assert not table.failed
    assert rms(table.corners_px, truth[shown]) < 0.05
    assert table.meta["detection"].startswith("tracked ")
