"""Issue 29, items 6, 7 and 15: the result set is all-or-nothing, a moved session stops the run, no temp file stays.

Faults are injected where the issue found them: a full disk at every write of
an estimate's commit, a kill between the renames (the rename raising a
BaseException that nothing in lps catches, as a SIGKILL would stop it there),
the session folder moved during a capture and during an estimate.
"""
from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path

import pytest

from lps_gui.cli import main
from lps_gui.errors import StorageError
from lps_gui.io import file_set
from lps_gui.io.atomic import storage_error
from lps_gui.io.results.history import HISTORY_DIR, LATEST_FILE

SET = ("results.json", "positions.csv", "summary.csv", f"{HISTORY_DIR}/{LATEST_FILE}")


class Killed(BaseException):
    """Stands for a SIGKILL: not an Exception, so no handler of lps runs."""


def set_bytes(folder: Path) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in SET}


def temps(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*.tmp")]


@pytest.fixture()
def estimated(point_session):
    assert main(["estimate", str(point_session)]) == 0
    return point_session


def test_item6_a_full_disk_at_any_write_of_the_commit_keeps_the_old_set_and_latest(estimated, monkeypatch, capsys):
    old = set_bytes(estimated)
    real = file_set.write_temp
    for fail_at in range(1, 12):
        calls = {"n": 0}

        def write_temp(path, data, fail_at=fail_at):
            calls["n"] += 1
            if calls["n"] == fail_at:
                raise storage_error(path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
            return real(path, data)

        monkeypatch.setattr(file_set, "write_temp", write_temp)
        code = main(["estimate", str(estimated), "--method", "pnp"])
        if calls["n"] < fail_at:  # every write of the commit was failed once: done
            assert code == 0
            break
        assert code == 2, fail_at
        assert "previous file is kept" in capsys.readouterr().err
        assert set_bytes(estimated) == old, f"write {fail_at} failed but the set changed"
        assert not temps(estimated)
    else:
        pytest.fail("the commit never completed")
    assert set_bytes(estimated) != old  # the last run wrote the new set


def test_item6_a_full_disk_writing_the_journal_keeps_the_old_set(estimated, monkeypatch, capsys):
    old = set_bytes(estimated)

    def journal(path, data):
        raise storage_error(path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))

    monkeypatch.setattr(file_set, "write_bytes_atomic", journal)
    assert main(["estimate", str(estimated), "--method", "pnp"]) == 2
    assert set_bytes(estimated) == old and not temps(estimated)


def _kill_after_renames(monkeypatch, folder: Path, n_done: int) -> None:
    """The top-level commit is killed after ``n_done`` of its renames (the history copy before it completes)."""
    real = os.replace
    calls = {"n": 0}

    def replace(src, dst):
        if Path(dst).parent in (folder, folder / HISTORY_DIR) and (folder / file_set.JOURNAL).exists():
            calls["n"] += 1
            if calls["n"] > n_done:
                raise Killed()
        return real(src, dst)

    monkeypatch.setattr(file_set.os, "replace", replace)


@pytest.mark.parametrize("n_done", [0, 1, 2, 3])
def test_item6_a_kill_between_the_renames_is_finished_by_the_next_reader(estimated, monkeypatch, n_done):
    from lps_gui.io.results.model import read_results

    old = set_bytes(estimated)
    _kill_after_renames(monkeypatch, estimated, n_done)
    with pytest.raises(Killed):
        main(["estimate", str(estimated), "--method", "pnp"])
    monkeypatch.undo()
    assert (estimated / file_set.JOURNAL).exists()
    results = read_results(estimated)  # any reader finishes the commit first
    new = set_bytes(estimated)
    assert not (estimated / file_set.JOURNAL).exists()
    assert results.method == "pnp" and new["results.json"] != old["results.json"]
    latest = (estimated / HISTORY_DIR / LATEST_FILE).read_text()
    entry = estimated / HISTORY_DIR / __import__("json").loads(latest)["latest"]
    for name in ("results.json", "positions.csv", "summary.csv"):  # one set: the history copy of the same estimate
        assert new[name] == (entry / name).read_bytes(), name
    assert not temps(estimated)


def test_item6_temp_files_of_a_killed_run_are_removed_at_the_next_start(estimated):
    dead = 2**22 + 12345  # above any pid_max: no such process
    orphans = [estimated / f".results.json.{dead}-abc123.tmp", estimated / "images" / f".000001.png.{dead}-x.tmp",
               estimated / f".corners.vnl.{dead}-q.tmp", estimated / f".report.pdf.{dead}-r.tmp"]
    (estimated / "images").mkdir(exist_ok=True)
    for p in orphans:
        p.write_bytes(b"half")
    live = estimated / f".report.pdf.{os.getpid()}-live.tmp"  # a writer that still runs keeps its temp file
    live.write_bytes(b"being written")
    assert main(["estimate", str(estimated)]) == 0
    assert not any(p.exists() for p in orphans)
    assert live.exists()


def test_item6_export_colmap_over_an_older_export_is_one_set(estimated, tmp_path, monkeypatch):
    out = tmp_path / "colmap"
    assert main(["export", str(estimated), "--format", "colmap", "--out", str(out)]) == 0
    old = {p.name: p.read_bytes() for p in out.iterdir()}
    real = os.replace
    calls = {"n": 0}

    def replace(src, dst):
        if Path(dst).parent == out and Path(dst).suffix == ".txt" and Path(dst).name != "excluded.txt":
            calls["n"] += 1
            if calls["n"] == 2:
                raise Killed()
        return real(src, dst)

    assert main(["estimate", str(estimated), "--method", "pnp"]) == 0
    monkeypatch.setattr(file_set.os, "replace", replace)
    with pytest.raises(Killed):
        main(["export", str(estimated), "--format", "colmap", "--out", str(out)])
    monkeypatch.undo()
    file_set.recover_file_set(out)  # what the next export into the folder does first
    now = {p.name: p.read_bytes() for p in out.iterdir() if p.suffix == ".txt"}
    assert now["images.txt"] != old["images.txt"]  # rolled forward: the new set (the others' content is the same)
    assert not (out / file_set.JOURNAL).exists()
    assert not temps(out)


# ----------------------------------------------------------------------------- item 7
def test_item7_a_session_moved_mid_capture_stops_and_nothing_reappears_at_the_old_path(tmp_path):
    from tests.capture.helpers import start_capture

    folder = tmp_path / "N"
    session, stage, camera, engine = start_capture(folder)
    moved = tmp_path / "N2"
    real_grab = camera.grab
    count = {"n": 0}

    def grab():
        count["n"] += 1
        if count["n"] == 4:
            shutil.move(folder, moved)
        return real_grab()

    camera.grab = grab
    with pytest.raises(StorageError, match="moved or removed"):
        engine.run()
    assert not folder.exists()
    listed = (moved / "captures.jsonl").read_text().splitlines()
    assert len(listed) == 3


def test_item7_a_session_removed_mid_estimate_is_not_recreated(estimated, monkeypatch, capsys):
    from lps_gui.pipeline import estimate as pipeline_estimate
    real = pipeline_estimate.build_results

    def build_results(session, *a, **k):
        out = real(session, *a, **k)
        shutil.move(session.folder, session.folder.with_name("moved"))
        return out

    monkeypatch.setattr(pipeline_estimate, "build_results", build_results)
    assert main(["estimate", str(estimated)]) == 2
    assert "moved or removed" in capsys.readouterr().err
    assert not estimated.exists()


# ----------------------------------------------------------------------------- item 15
def test_item15_a_kill_between_the_two_session_json_writes_is_repaired_by_the_resume(tmp_path, monkeypatch):
    from lps_gui.io.session import Session

    out = tmp_path / "N"
    real = Session.save_meta

    def killed(self):
        raise Killed()

    monkeypatch.setattr(Session, "save_meta", killed)
    with pytest.raises(Killed):
        main(["capture", "--out", str(out), "--stop", "4", "--step", "2"])
    monkeypatch.setattr(Session, "save_meta", real)
    assert "spec" not in Session.open(out).meta["stage"]
    assert main(["capture", "--resume", str(out)]) == 0
    meta = Session.open(out).meta
    assert meta["stage"]["spec"] == "sim" and meta["camera"]["spec"] == "sim"


def test_item12_a_full_disk_in_a_writer_without_its_own_check_is_one_line_not_a_bug(tmp_path, monkeypatch, capsys):
    from lps_gui.pipeline.demos import run as demo
    def full(*_a, **_k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "d" / "intrinsics" / "view_003.png"))

    monkeypatch.setattr(demo, "run_demo", full)
    assert main(["demo", "--quick", "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "No space left" in err[0] and "internal error" not in err[0] and "view_003.png" in err[0]
