"""Items 3-7 and 16 of issue 17: one writer per session, nothing read or written outside it, stale corners."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.cli import main
from lps_gui.errors import InputError
from lps_gui.io.session import Session

ROOT = Path(__file__).resolve().parents[2]
HOLD = ("import sys; from lps_gui.io.session_lock import SessionLock\n"
        "with SessionLock(sys.argv[1], 'lps capture --resume S'):\n"
        "    print('held', flush=True); sys.stdin.read()\n")


def err_line(capsys) -> str:
    return capsys.readouterr().err.strip().splitlines()[-1]


@pytest.fixture()
def held(point_session):
    """Another process holding the session (as a running capture would); released at the end."""
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(point_session)], cwd=ROOT, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "held"
        yield proc
    finally:
        proc.communicate("", timeout=30)


# ------------------------------------------------------------------ item 3: session lock
def test_item3_estimate_while_another_process_holds_the_session_is_refused_naming_it(point_session, held, capsys):
    assert main(["estimate", str(point_session)]) == 2
    err = err_line(capsys)
    assert f"in use by pid {held.pid}" in err and "lps capture --resume S" in err
    assert not (point_session / "results.json").exists()


def test_item3_detect_and_capture_resume_are_refused_too(imaged_session, capsys):
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(imaged_session)], cwd=ROOT, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "held"
        lines = (imaged_session / "captures.jsonl").read_text().splitlines()
        (imaged_session / "captures.jsonl").write_text("\n".join(lines[:3]) + "\n")  # an interrupted capture
        assert main(["capture", "--resume", str(imaged_session)]) == 2
        assert f"in use by pid {proc.pid}" in err_line(capsys)
        assert len((imaged_session / "captures.jsonl").read_text().splitlines()) == 3  # nothing appended
        assert main(["detect", str(imaged_session), "--workers", "1"]) == 2
        assert f"in use by pid {proc.pid}" in err_line(capsys)
        assert not (imaged_session / "corners.vnl").exists()
    finally:
        proc.communicate("", timeout=30)
    assert main(["capture", "--resume", str(imaged_session)]) == 0  # released: the resume completes
    assert len(Session.open(imaged_session).records()) == 6
    assert not (imaged_session / ".lock").exists()


def test_item3_a_duplicated_index_in_captures_jsonl_is_an_error_naming_the_line(point_session, capsys):
    path = point_session / "captures.jsonl"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines + [lines[2]]) + "\n")
    with pytest.raises(InputError, match=f"line {len(lines) + 1} repeats index"):
        Session.open(point_session).records()
    assert main(["estimate", str(point_session)]) == 2
    assert f"line {len(lines) + 1} repeats index" in err_line(capsys)


# ------------------------------------------------------------------ item 4: symlinked session files
def test_item4_a_symlinked_captures_jsonl_is_refused_and_its_target_untouched(imaged_session, tmp_path, capsys):
    elsewhere = tmp_path / "precious.txt"
    content = (imaged_session / "captures.jsonl").read_bytes()[:-40]  # a "torn" last line, as after a crash
    elsewhere.write_bytes(content)
    (imaged_session / "captures.jsonl").unlink()
    (imaged_session / "captures.jsonl").symlink_to(elsewhere)
    assert main(["capture", "--resume", str(imaged_session)]) == 2
    assert "symbolic link" in err_line(capsys)
    assert elsewhere.read_bytes() == content


def test_item4_append_line_durable_never_follows_a_symlink(tmp_path):
    from lps_gui.io.atomic import append_line_durable

    target = tmp_path / "other.log"
    target.write_bytes(b"line one\ntorn")
    (tmp_path / "link.jsonl").symlink_to(target)
    with pytest.raises(InputError, match="symbolic link"):
        append_line_durable(tmp_path / "link.jsonl", "{}")
    assert target.read_bytes() == b"line one\ntorn"


# ------------------------------------------------------------------ item 5: stale corners and results
def _replace_image(session_dir: Path, index: int) -> str:
    """Replace one image with another (shifted) one and list its new sha256, as a re-capture would."""
    import hashlib

    path = session_dir / "captures.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    rec = records[index]
    image = cv2.imread(str(session_dir / rec["file"]), cv2.IMREAD_GRAYSCALE)
    shifted = np.roll(image, 7, axis=1)
    ok, buf = cv2.imencode(".png", shifted)
    (session_dir / rec["file"]).write_bytes(buf.tobytes())
    rec["sha256"] = hashlib.sha256(buf.tobytes()).hexdigest()
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return rec["file"]


def test_item5_a_replaced_image_is_detected_again(imaged_session, capsys):
    from lps_gui.io.corners.vnl import read_corners_vnl

    assert main(["detect", str(imaged_session), "--workers", "1"]) == 0
    n = Session.open(imaged_session).board().n_corners
    old = read_corners_vnl(imaged_session / "corners.vnl", n)
    name = _replace_image(imaged_session, 2)
    capsys.readouterr()
    assert main(["detect", str(imaged_session), "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "kept 5" in out  # not "kept 6": the replaced view is detected again
    new = read_corners_vnl(imaged_session / "corners.vnl", n)
    shift = new.corners_px[new.index()[name], :, 0] - old.corners_px[old.index()[name], :, 0]
    assert np.allclose(shift, 7.0, atol=0.3)


def test_item5_estimate_refuses_corners_of_a_replaced_image(imaged_session, capsys):
    assert main(["detect", str(imaged_session), "--workers", "1"]) == 0
    _replace_image(imaged_session, 2)
    assert main(["estimate", str(imaged_session)]) == 2
    err = err_line(capsys)
    assert "older image" in err and "lps detect" in err


@pytest.mark.gui
def test_item5_report_says_when_results_are_stale(point_session, capsys):
    assert main(["estimate", str(point_session)]) == 0
    assert main(["report", str(point_session)]) == 0
    path = point_session / "captures.jsonl"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:-1]) + "\n")  # the session changed after the estimate
    capsys.readouterr()
    assert main(["report", str(point_session)]) == 3
    err = err_line(capsys)
    assert "stale" in err and "captures.jsonl" in err and "lps estimate" in err


# ------------------------------------------------------------------ item 6: paths outside the session
@pytest.mark.parametrize("bad", ["../outside.png", "/etc/passwd", "/dev/zero", "images/../../outside.png"])
def test_item6_files_outside_the_session_are_refused(imaged_session, capsys, bad):
    path = imaged_session / "captures.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    records[1]["file"] = bad
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    assert main(["detect", str(imaged_session), "--workers", "1"]) == 2
    err = err_line(capsys)
    assert "line 2" in err and "outside the session folder" in err


def test_item6_a_symlink_inside_the_session_to_a_device_is_not_read(imaged_session, capsys):
    path = imaged_session / "captures.jsonl"
    first = json.loads(path.read_text().splitlines()[0])["file"]
    (imaged_session / first).unlink()
    (imaged_session / first).symlink_to("/dev/zero")
    assert main(["detect", str(imaged_session), "--workers", "1"]) == 3  # that view fails, the others are detected
    err = capsys.readouterr().err
    assert f"failed: {first}:" in err and "symbolic link" in err


def test_item6_a_symlinked_images_folder_leading_outside_is_refused(imaged_session, tmp_path, capsys):
    import shutil

    outside = tmp_path / "outside-images"
    shutil.move(str(imaged_session / "images"), outside)
    (imaged_session / "images").symlink_to(outside)
    assert main(["detect", str(imaged_session), "--workers", "1"]) == 3
    assert "outside the session folder" in capsys.readouterr().err


# ------------------------------------------------------------------ item 7: devices on resume
def test_item7_resume_never_opens_a_device_named_in_session_json(tmp_path, capsys, monkeypatch):
    from lps_gui import hardware

    opened = []
    monkeypatch.setattr(hardware, "open_stage", lambda spec, **kw: opened.append(spec) or (_ for _ in ()).throw(AssertionError(spec)))
    frames = tmp_path / "frames"
    frames.mkdir()
    cv2.imwrite(str(frames / "f0.png"), np.zeros((24, 32), np.uint8))
    board = tmp_path / "board.json"
    board.write_text(json.dumps({"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}))
    out = tmp_path / "s"
    Session.create(out, __import__("lps_gui.io.board_file", fromlist=["read_board"]).read_board(board),
                   __import__("lps_gui.core.planning.plan", fromlist=["Plan"]).Plan(targets_mm=(0.0, 1.0), settle_s=0.0),
                   camera={"spec": str(frames)}, stage={"spec": "grbl:socket://203.0.113.9:23"})
    assert main(["capture", "--resume", str(out)]) == 2
    err = err_line(capsys)
    assert "give --stage and --camera" in err and "socket://203.0.113.9:23" in err
    assert opened == []


# ------------------------------------------------------------------ item 16: time as ISO 8601
def test_item16_iso_8601_times_are_accepted_and_bad_fields_named(point_session, capsys):
    path = point_session / "captures.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    for k, r in enumerate(records):
        r["time"] = f"2026-11-30T10:00:{k:02d}+00:00" if k % 2 else r.get("time", 0)
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    recs = Session.open(point_session).records()
    from datetime import datetime, timezone

    assert recs[1].time == datetime(2026, 11, 30, 10, 0, 1, tzinfo=timezone.utc).timestamp()
    records[3]["time"] = "yesterday"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    assert main(["estimate", str(point_session)]) == 2
    err = err_line(capsys)
    assert "line 4" in err and "'time'" in err and "ISO 8601" in err
