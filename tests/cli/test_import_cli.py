"""`lps import` (SPEC 16): the paper's workflow from a folder of rendered images, in place, names, a CSV, and every
bad input as a one-line error that leaves nothing behind."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.cli import main as lps_main
from lps_gui.io.atomic import sha256_file
from lps_gui.io.session import Session


def _lps(*args) -> int:
    return lps_main([str(a) for a in args])


def _simulated(tmp_path: Path, *switches: str) -> Path:
    """A rendered simulated session (the captured session), its board and intrinsics written out as a user has them."""
    sim = tmp_path / "sim"
    assert _lps("simulate", sim, "--stops", "6", *switches) == 0
    meta = json.loads((sim / "session.json").read_text())
    (tmp_path / "board.json").write_text(json.dumps(meta["board"]))
    (tmp_path / "intrinsics.json").write_text(json.dumps(meta["intrinsics"]))
    return sim


def _photos(sim: Path, folder: Path, name: str = "photo{n}.png") -> dict[str, tuple[bytes, float]]:
    """The session's images copied out under neutral names numbered from 1 (photo10 sorts after photo9 only
    naturally); returns each copy's bytes and mtime."""
    folder.mkdir()
    for r in Session.open(sim).records():
        shutil.copy2(sim / r.file, folder / name.format(n=r.index + 1, mm=r.target_mm))
    return {p.name: (p.read_bytes(), p.stat().st_mtime) for p in folder.iterdir()}


def _positions(session: Path) -> list[dict]:
    return json.loads((session / "results.json").read_text())["positions"]


def test_import_detect_estimate_gives_the_captured_sessions_positions(tmp_path):
    """The paper's workflow: a folder of images and a step; detect and estimate as on the captured session, and the
    measured positions are the same numbers."""
    sim = _simulated(tmp_path)
    photos = tmp_path / "photos"
    before = _photos(sim, photos)
    imported = tmp_path / "imported"
    assert _lps("import", photos, "--out", imported, "--board", tmp_path / "board.json", "--intrinsics",
                tmp_path / "intrinsics.json", "--step", "2") == 0
    for session in (sim, imported):
        assert _lps("detect", session) == 0
        assert _lps("estimate", session) == 0
    got, want = _positions(imported), _positions(sim)
    assert len(got) == len(want) == 6
    assert [p["measured_mm"] for p in got] == [p["measured_mm"] for p in want]
    assert [(p["target_mm"], p["direction"], p["run"]) for p in got] == [(p["target_mm"], p["direction"], p["run"]) for p in want]
    # captures.jsonl as SPEC 16 says: reported = target, source import, the sha256 of the image
    session = Session.open(imported)
    assert session.meta["stage"] == {"driver": "import"}
    lines = [json.loads(line) for line in session.captures_path.read_text().splitlines()]
    assert all(d["source"] == "import" and d["reported_mm"] == d["target_mm"] for d in lines)
    assert [d["file"] for d in lines] == [f"images/photo{n}.png" for n in range(1, 7)]
    assert all(d["sha256"] == sha256_file(imported / d["file"]) == sha256_file(photos / Path(d["file"]).name) for d in lines)
    assert {p.name: (p.read_bytes(), p.stat().st_mtime) for p in photos.iterdir()} == before  # never modified
    assert _lps("report", imported) == 0 and (imported / "report.pdf").stat().st_size > 0


def test_a_step_with_both_directions_lists_what_capture_listed(tmp_path):
    sim = _simulated(tmp_path, "--directions", "both", "--runs", "2")
    photos = tmp_path / "photos"
    _photos(sim, photos, "img_{n}.png")
    out = tmp_path / "imported"
    assert _lps("import", photos, "--out", out, "--board", tmp_path / "board.json", "--step", "2",
                "--directions", "both", "--runs", "2") == 0
    fields = ("index", "run", "direction", "target_mm", "reported_mm", "sha256")
    assert [tuple(getattr(r, k) for k in fields) for r in Session.open(out).records()] == \
        [tuple(getattr(r, k) for k in fields) for r in Session.open(sim).records()]


def test_in_place_writes_the_session_beside_the_images(tmp_path):
    sim = _simulated(tmp_path)
    photos = tmp_path / "photos"
    before = _photos(sim, photos, "pos_{mm}.png")
    assert _lps("import", photos, "--in-place", "--board", tmp_path / "board.json", "--intrinsics",
                tmp_path / "intrinsics.json", "--from-names", "pos_{mm}.png") == 0
    session = Session.open(photos)
    assert [r.file for r in session.records()] == [f"pos_{mm}.png" for mm in (0.0, 2.0, 4.0, 6.0, 8.0, 10.0)]
    assert [r.target_mm for r in session.records()] == [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
    assert sorted(p.name for p in photos.iterdir()) == sorted([*before, "session.json", "captures.jsonl"])  # no images/
    assert _lps("detect", photos) == 0 and _lps("estimate", photos) == 0
    assert [p["measured_mm"] for p in _positions(photos)] == [p["measured_mm"] for p in _positions_of(sim)]
    assert {n: (photos / n).read_bytes() for n in before} == {n: b for n, (b, _) in before.items()}


def _positions_of(sim: Path) -> list[dict]:
    assert _lps("detect", sim) == 0 and _lps("estimate", sim) == 0
    return _positions(sim)


def test_a_csv_gives_files_targets_directions_and_runs(tmp_path):
    photos = _tiny_images(tmp_path / "photos", ["a.png", "b.png", "c.png", "d.png"])
    (photos / "sub").mkdir()
    shutil.move(photos / "d.png", photos / "sub" / "d.png")
    csv = tmp_path / "pos.csv"
    csv.write_text("file,target,direction,run\nc.png,0,+,1\na.png,5,+,1\nb.png,5,-,1\nsub/d.png,0,-,1\n")
    out = tmp_path / "s"
    assert _lps("import", photos, "--out", out, "--board", _board(tmp_path), "--positions", csv) == 0
    records = Session.open(out).records()
    assert [(r.file, r.target_mm, r.direction, r.run) for r in records] == [
        ("images/c.png", 0.0, "+", 1), ("images/a.png", 5.0, "+", 1), ("images/b.png", 5.0, "-", 1),
        ("images/sub/d.png", 0.0, "-", 1)]
    assert Session.open(out).plan().directions == "both"


def _tiny_images(folder: Path, names: list[str], size: tuple[int, int] = (32, 24)) -> Path:
    """Small distinct PNGs (the import reads headers and bytes; nothing here is detected)."""
    folder.mkdir(parents=True, exist_ok=True)
    for i, name in enumerate(names):
        image = np.full((size[1], size[0]), 10 * i + 5, np.uint8)
        assert cv2.imwrite(str(folder / name), image)
    return folder


def _board(tmp_path: Path) -> Path:
    path = tmp_path / "board.json"
    path.write_text(json.dumps({"type": "chessboard", "inner_corners": [9, 6], "square_mm": 10.0}))
    return path


def _bad_name(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["pos_1.png", "pos_2.png", "pos_end.png"])
    return ["--from-names", "pos_{mm}.png"]


def _csv_missing_file(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a.png", "b.png"])
    (tmp / "p.csv").write_text("file,target\na.png,0\nlost.png,1\nb.png,2\n")
    return ["--positions", tmp / "p.csv"]


def _csv_twice(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a.png", "b.png"])
    (tmp / "p.csv").write_text("a.png,0\nb.png,1\na.png,2\n")
    return ["--positions", tmp / "p.csv"]


def _same_bytes(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a.png", "b.png"])
    shutil.copy(photos / "a.png", photos / "c.png")
    return ["--step", "1"]


def _mixed_sizes(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a1.png", "a2.png"])
    _tiny_images(photos, ["a3.png"], size=(40, 24))
    return ["--step", "1"]


def _unreadable(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a1.png", "a2.png"])
    (photos / "a3.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 40)
    return ["--step", "1"]


def _not_an_image(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a1.png", "a2.png"])
    (photos / "notes.txt").write_text("rig at 20 C\n")
    return ["--step", "1"]


def _intrinsics_size(photos: Path, tmp: Path) -> list:
    _tiny_images(photos, ["a1.png", "a2.png"])
    from lps_gui.core.geometry.camera_model import CameraIntrinsics
    from lps_gui.io.intrinsics_file import write_intrinsics

    write_intrinsics(tmp / "k.json", CameraIntrinsics.from_values((640, 480), 500, 500, 320, 240))
    return ["--step", "1", "--intrinsics", tmp / "k.json"]


@pytest.mark.parametrize("make, pattern", [
    (_bad_name, r"photos/pos_end\.png: the name does not match --from-names 'pos_\{mm\}\.png'"),
    (_csv_missing_file, r"p\.csv: line 3: lost\.png not found in .*photos"),
    (_csv_twice, r"p\.csv: line 3: a\.png is listed again \(line 1\)"),
    (_same_bytes, r"photos/c\.png: the same image as a\.png"),
    (_mixed_sizes, r"photos/a3\.png: 40x24 px, but a1\.png is 32x24"),
    (_unreadable, r"photos/a3\.png: not an? .*image"),  # the header check's words
    (_not_an_image, r"photos/notes\.txt: not an image file"),
    (_intrinsics_size, r"photos/a1\.png: 32x24 px, but the intrinsics are for 640x480"),
])
def test_bad_inputs_are_one_line_errors_and_leave_nothing(tmp_path, capsys, make, pattern):
    photos = tmp_path / "photos"
    switches = make(photos, tmp_path)
    before = {p: p.read_bytes() for p in photos.rglob("*") if p.is_file()}
    out = tmp_path / "s"
    assert _lps("import", photos, "--out", out, "--board", _board(tmp_path), *switches) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("lps import:")]  # not the bar
    assert len(errors) == 1 and re.match(r"lps import: error: .*" + pattern, errors[0]), errors
    assert not out.exists()
    assert {p: p.read_bytes() for p in photos.rglob("*") if p.is_file()} == before


def test_an_existing_session_is_not_overwritten(tmp_path, capsys):
    photos = _tiny_images(tmp_path / "photos", ["a.png", "b.png", "c.png"])
    out = tmp_path / "s"
    assert _lps("import", photos, "--out", out, "--board", _board(tmp_path), "--step", "1") == 0
    kept = (out / "captures.jsonl").read_bytes()
    capsys.readouterr()
    assert _lps("import", photos, "--out", out, "--board", _board(tmp_path), "--step", "2") == 2
    assert re.search(r"s: already holds a session \(session\.json\)", capsys.readouterr().err)
    assert (out / "captures.jsonl").read_bytes() == kept
    assert _lps("import", photos, "--in-place", "--board", _board(tmp_path), "--step", "1") == 0
    assert _lps("import", photos, "--in-place", "--board", _board(tmp_path), "--step", "1") == 2
    assert "photos: already holds a session" in capsys.readouterr().err
    assert _lps("capture", "--resume", out) == 2  # no stage went with these images: a capture cannot go on
    assert "imported images (lps import), not a capture; nothing to resume" in capsys.readouterr().err
    assert (out / "captures.jsonl").read_bytes() == kept


@pytest.mark.parametrize("switches, match", [
    (["--step", "1", "--from-names", "{mm}.png"], "give the positions one way"),
    ([], "give the positions one way"),
    (["--from-names", "{mm}.png", "--runs", "2"], "--directions and --runs go with --step"),
    (["--step", "1", "--in-place", "--out", "elsewhere"], "--in-place writes the session into"),
])
def test_switches_that_do_not_go_together(tmp_path, capsys, switches, match):
    photos = _tiny_images(tmp_path / "photos", ["a.png", "b.png"])
    args = ["import", photos, "--board", _board(tmp_path), *switches]
    if "--in-place" not in switches:
        args += ["--out", tmp_path / "s"]
    assert _lps(*args) == 2
    assert match in capsys.readouterr().err

