"""Items 8-15 and 17 of issue 17: log location, resource limits, confident wrong answers, CLI rules."""
from __future__ import annotations

import json
import os
import stat
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.cli import main
from lps_gui.errors import InputError
from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl
from lps_gui.io.session import Session

BOARD = {"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}


def err_line(capsys) -> str:
    return capsys.readouterr().err.strip().splitlines()[-1]


def huge_png(path: Path, w: int = 30000, h: int = 30000) -> Path:
    """A valid PNG header declaring w x h grey pixels, with a tiny (not decodable) body: what the header says counts."""
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    chunk = lambda kind, data: struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 1000)) + chunk(b"IEND", b""))
    return path


# ------------------------------------------------------------------ item 8: log file
def test_item8_log_goes_to_the_users_state_folder_created_0700(tmp_path, monkeypatch):
    from lps_gui.cli import log_file
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    handler, where = log_file.open_log_handler()
    try:
        assert where == str(tmp_path / "state" / "lps-calib" / "lps.log")
        assert stat.S_IMODE(os.stat(tmp_path / "state" / "lps-calib").st_mode) == 0o700
    finally:
        handler.close()
    monkeypatch.delenv("XDG_STATE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert log_file.log_path() == tmp_path / "home" / ".local" / "state" / "lps-calib" / "lps.log"


def test_item8_a_symlinked_or_folder_log_is_not_followed_and_not_fatal(tmp_path, monkeypatch):
    from lps_gui.cli import log_file
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path))
    (tmp_path / "lps-calib").mkdir(mode=0o700)
    victim = tmp_path / "victim"
    victim.write_text("keep")
    (tmp_path / "lps-calib" / "lps.log").symlink_to(victim)
    handler, where = log_file.open_log_handler()
    assert where.startswith("no log file") and victim.read_text() == "keep"
    (tmp_path / "lps-calib" / "lps.log").unlink()
    (tmp_path / "lps-calib" / "lps.log").mkdir()
    handler, where = log_file.open_log_handler()
    assert where.startswith("no log file")


def test_item8_the_fixed_tmp_log_name_is_gone():
    import lps_gui.cli as cli

    assert not hasattr(cli, "LOG_PATH")


# ------------------------------------------------------------------ item 9: pixel count before decoding
def test_item9_detect_refuses_a_30000px_png_before_decoding(tmp_path, capsys):
    (tmp_path / "board.json").write_text(json.dumps(BOARD))
    img = huge_png(tmp_path / "big.png")
    assert img.stat().st_size < 5000
    assert main(["detect", str(img), "--board", str(tmp_path / "board.json"), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert "30000x30000" in err and "Mpx" in err


def test_item9_intrinsics_refuses_it_too(tmp_path, capsys):
    (tmp_path / "board.json").write_text(json.dumps(BOARD))
    img = huge_png(tmp_path / "big.png")
    assert main(["intrinsics", str(img), "--board", str(tmp_path / "board.json"), "--workers", "1",
                 "--out", str(tmp_path / "i.json")]) == 2
    assert "30000x30000" in capsys.readouterr().err
    assert not (tmp_path / "i.json").exists()


@pytest.mark.parametrize("ext", [".png", ".bmp", ".tif", ".jpg", ".pgm"])
def test_item9_header_sizes_of_every_format_we_read(tmp_path, ext):
    from lps_gui.core.image_header import image_size_from_header

    path = tmp_path / f"x{ext}"
    cv2.imwrite(str(path), np.zeros((37, 53), np.uint8))
    assert image_size_from_header(path.read_bytes()[:65536]) == (53, 37)


def test_item9_folder_replay_checks_before_decoding(tmp_path):
    from lps_gui.camera.folder_replay import FolderReplayCamera

    huge_png(tmp_path / "000.png")
    cam = FolderReplayCamera(tmp_path)
    with pytest.raises(InputError, match="30000x30000"):
        cam.open()
        cam.grab()


# ------------------------------------------------------------------ item 10: plan limits before building
@pytest.mark.parametrize("args,needle", [
    (["--start", "0", "--stop", "1e9", "--step", "1"], "over the limit"),
    (["--start", "0", "--stop", "10", "--step", "1e-6"], "below"),
    (["--targets", "0,1e-9"], "one position"),
    (["--start", "0", "--stop", "10", "--step", "1", "--overshoot", "-1"], "overshoot_mm"),
    (["--start", "0", "--stop", "10", "--step", "1", "--settle", "-0.5"], "settle_s"),
    (["--start", "0", "--stop", "10", "--step", "1", "--feed", "0"], "feed_mm_min"),
    (["--targets", "0,nan,2"], "finite"),
])
def test_item10_plan_limits_are_checked_before_anything_is_built(tmp_path, capsys, args, needle):
    import tracemalloc

    tracemalloc.start()
    code = main(["capture", "--out", str(tmp_path / "s"), *args])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert code == 2
    assert needle in err_line(capsys)
    assert peak < 200e6  # nothing the size of the plan was built
    assert not (tmp_path / "s" / "session.json").exists()


# ------------------------------------------------------------------ item 11: non-convergence, absurd noise
def test_item11_absurd_corner_noise_is_a_warning_and_a_non_zero_exit(point_session, capsys):
    session = Session.open(point_session)
    table = read_corners_vnl(session.corners_path, session.board().n_corners)
    rng = np.random.default_rng(0)
    table.corners_px = table.corners_px + rng.normal(0, 40.0, table.corners_px.shape)  # corners off by tens of px
    write_corners_vnl(session.corners_path, table)
    code = main(["estimate", str(point_session), "--no-outliers"])
    err = capsys.readouterr().err
    assert code == 4, err
    assert "implausible" in err or "did not converge" in err
    assert (point_session / "results.json").exists()  # written, and said not to be trusted


def test_item11_the_exit_status_is_documented(capsys):
    with pytest.raises(SystemExit):
        main(["estimate", "--help"])
    assert "4 results written but not trustworthy" in capsys.readouterr().out


def test_item11_non_convergence_is_reported():
    from lps_gui.io.results.sections import Parameters
    from lps_gui.pipeline.session_checks import result_doubts

    assert result_doubts(Parameters.from_dict({"converged": True, "sigma_px": 0.2})) == []
    assert "did not converge" in result_doubts(Parameters.from_dict({"converged": False, "sigma_px": 0.2, "iterations": 50}))[0]
    assert "implausible" in result_doubts(Parameters.from_dict({"converged": True, "sigma_px": 1.2e13}))[0]


# ------------------------------------------------------------------ item 12: duplicate views in intrinsics
def test_item12_copies_of_one_image_are_refused_for_intrinsics(tmp_path, capsys):
    from lps_gui.cli import main as lps
    assert lps(["simulate", str(tmp_path / "set"), "--intrinsics-set", "--views", "4", "--seed", "1"]) == 0
    images = sorted((tmp_path / "set").rglob("*.png"))
    assert len(images) >= 1
    copies = tmp_path / "copies"
    copies.mkdir()
    for k in range(4):
        (copies / f"c{k}.png").write_bytes(images[0].read_bytes())
    board = next((tmp_path / "set").rglob("board.json"), None)
    if board is None:
        board = tmp_path / "board.json"
        board.write_text(json.dumps(Session.open(tmp_path / "set").meta["board"]))
    capsys.readouterr()
    assert lps(["intrinsics", str(copies), "--board", str(board), "--workers", "1", "--out", str(tmp_path / "i.json")]) == 2
    err = err_line(capsys)
    assert "distinct" in err and "varied poses" in err
    assert not (tmp_path / "i.json").exists()


def test_item12_duplicate_views_are_found():
    from lps_gui.core.geometry.view_geometry import duplicate_views

    rng = np.random.default_rng(1)
    a = rng.uniform(0, 600, (54, 2))
    views = np.stack([a, a + 0.1, rng.uniform(0, 600, (54, 2)), a + 5.0])
    assert duplicate_views(views) == [(0, 1)]


# ------------------------------------------------------------------ item 13: corners on one line
def test_item13_a_view_with_all_corners_on_one_row_is_refused(point_session, capsys):
    session = Session.open(point_session)
    table = read_corners_vnl(session.corners_path, session.board().n_corners)
    table.corners_px[3, :, 1] = table.corners_px[3, 0, 1]  # every corner on the first row's line
    write_corners_vnl(session.corners_path, table)
    assert main(["estimate", str(point_session)]) == 2
    err = err_line(capsys)
    assert "on one line" in err and table.names[3] in err


# ------------------------------------------------------------------ item 14: stage short of the target
def test_item14_a_stage_that_stops_short_pauses_the_capture(tmp_path):
    from tests.capture.helpers import start_capture
    from tests.reliability.conftest import PLAN6

    session, stage, camera, engine = start_capture(tmp_path / "s", plan=PLAN6)
    real = stage.position_mm
    stage.position_mm = lambda *a: real(*a) - (0.5 if real(*a) > 7.0 else 0.0)  # stops 0.5 mm short beyond 7 mm
    summary = engine.run()
    assert summary.state == "paused"
    assert "after the move to 8.0000 mm" in summary.error and "-500.0 um" in summary.error
    assert [r.target_mm for r in session.records()] == [0.0, 2.0, 4.0, 6.0]  # the missed stop is not listed


# ------------------------------------------------------------------ item 15: one --out rule
def test_item15_estimate_out_with_a_json_suffix_is_a_file(point_session, tmp_path, capsys):
    assert main(["estimate", str(point_session), "--out", str(tmp_path / "est.json")]) == 0
    assert (tmp_path / "est.json").is_file()
    assert (tmp_path / "est-positions.csv").is_file() and (tmp_path / "est-summary.csv").is_file()


@pytest.mark.gui
def test_item15_report_out_an_existing_folder_gets_report_pdf(point_session, tmp_path, capsys):
    assert main(["estimate", str(point_session)]) == 0
    (tmp_path / "reports").mkdir()
    assert main(["report", str(point_session), "--out", str(tmp_path / "reports")]) == 0
    assert (tmp_path / "reports" / "report.pdf").read_bytes().startswith(b"%PDF")
    assert list((tmp_path / "reports").iterdir()) == [tmp_path / "reports" / "report.pdf"]
    assert main(["report", str(point_session), "--out", str(tmp_path / "r.txt")]) == 2
    assert ".pdf" in err_line(capsys)


def test_item15_the_rule_itself(tmp_path):
    from lps_gui.cli.out_path import resolve_out

    (tmp_path / "d").mkdir()
    assert resolve_out(tmp_path / "d", "corners.vnl", suffixes=(".vnl",)) == tmp_path / "d" / "corners.vnl"
    assert resolve_out(tmp_path / "c.vnl", "corners.vnl", suffixes=(".vnl",)) == tmp_path / "c.vnl"
    assert resolve_out(tmp_path / "new", "corners.vnl", suffixes=(".vnl",)) == tmp_path / "new" / "corners.vnl"
    assert (tmp_path / "new").is_dir()
    with pytest.raises(InputError, match="writes .vnl"):
        resolve_out(tmp_path / "c.csv", "corners.vnl", suffixes=(".vnl",))
    with pytest.raises(InputError, match="not found"):
        resolve_out(tmp_path / "missing" / "c.vnl", "corners.vnl", suffixes=(".vnl",))


# ------------------------------------------------------------------ item 17: messages that say what is wrong
def test_item17_detect_on_a_missing_path_says_not_found(tmp_path, capsys):
    assert main(["detect", str(tmp_path / "nonexistent")]) == 2
    err = err_line(capsys)
    assert "not found" in err and "--board" not in err


def test_item17_detect_on_a_folder_without_images_writes_nothing(tmp_path, capsys, monkeypatch):
    (tmp_path / "board.json").write_text(json.dumps(BOARD))
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "notes.txt").write_text("no images")
    (tmp_path / "empty").mkdir()
    monkeypatch.chdir(tmp_path)
    assert main(["detect", "--board", "board.json", "empty"]) == 2
    assert "no images" in err_line(capsys)
    cv2.imwrite(str(tmp_path / "junk" / "grey.png"), np.full((120, 160), 128, np.uint8))  # no board in it
    assert main(["detect", "--board", "board.json", "junk", "--workers", "1"]) == 2
    assert "found in none" in err_line(capsys)
    assert not (tmp_path / "corners.vnl").exists()


def test_item17_intrinsics_on_images_without_a_board_says_the_board_was_not_found(tmp_path, capsys):
    (tmp_path / "board.json").write_text(json.dumps(BOARD))
    for k in range(3):
        cv2.imwrite(str(tmp_path / f"blank{k}.png"), np.full((120, 160), 128, np.uint8))
    assert main(["intrinsics", str(tmp_path / "blank0.png"), str(tmp_path / "blank1.png"), str(tmp_path / "blank2.png"),
                 "--board", str(tmp_path / "board.json"), "--workers", "1", "--out", str(tmp_path / "i.json")]) == 2
    err = err_line(capsys)
    assert "board was found in none" in err and "could be read" not in err


def test_item17_no_track_is_honoured_on_sessions(imaged_session, capsys):
    assert main(["detect", str(imaged_session), "--workers", "1", "--no-track"]) == 0
    out = capsys.readouterr().out
    assert "tracked 0" in out and "full 6" in out


def test_item17_the_readme_links_no_file_outside_the_repository():
    import re

    root = Path(__file__).resolve().parents[2]
    text = (root / "README.md").read_text()
    assert "../" not in text, "README names a path outside the repository"
    assert "SPEC" not in text, "README cites the SPEC, which a clone does not have; cite docs/math.md"
    for target in re.findall(r"\]\(([^)#]+)", text):
        if "://" in target:
            continue
        assert (root / target).resolve().is_relative_to(root), f"README links {target}, outside the repository"
        assert (root / target).exists(), f"README links {target}, which does not exist"
