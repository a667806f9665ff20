"""Issue 39's independent bad-input campaign: each case it found, reproduced and answered with one line.

The cases that would exhaust memory on a reader without the check are tested
at the header check itself (what every image reader calls before decoding),
so the test fails on such a reader without the machine paying for it.
"""
from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from lps_gui.core.image_header import bytes_reader, check_image_header
from lps_gui.errors import HardwareError, InputError
from lps_gui.io.image_file import decode_image
from tests.reliability import bad_images

ROOT = Path(__file__).resolve().parents[2]


def _check(data: bytes, name: str = "x"):
    return check_image_header(data[:1 << 16], name, read_at=bytes_reader(data))


@pytest.mark.parametrize("make,needle", [
    (bad_images.gif_bomb, "not a PNG, TIFF, BMP, PGM/PPM, JPEG or WebP image"),
    (bad_images.hdr_bomb, "not a PNG, TIFF, BMP, PGM/PPM, JPEG or WebP image"),
    (bad_images.webp_bomb, r"16384x16384 \(268 Mpx\), over the 100 Mpx limit"),
    (lambda: bad_images.jpeg_with_sof_after(70_000, 30000, 30000), r"30000x30000 \(900 Mpx\), over the 100 Mpx limit"),
    (bad_images.bigtiff, "a BigTIFF"),
    (bad_images.duplicated_size_tiff, "a tag repeated in its image directory"),
])
def test_every_format_opencv_decodes_is_size_checked_or_refused_before_decoding(make, needle):
    with pytest.raises(InputError, match=needle) as exc:
        _check(make(), "v.img")
    assert str(exc.value).startswith("v.img: ") and "\n" not in str(exc.value)


def test_a_jpeg_whose_frame_header_follows_a_70_kb_comment_is_read_at_its_size():
    data = bad_images.jpeg_with_sof_after(70_000, 8, 8)
    assert _check(data) == (8, 8)
    assert decode_image(data, "c.jpg").shape == (8, 8)
    with pytest.raises(InputError, match="past its first 65536 bytes"):  # a reader that cannot reach it refuses
        check_image_header(data[:1 << 16], "c.jpg")


@pytest.mark.parametrize("make", [bad_images.nef_like, bad_images.dng_like])
def test_a_tiff_based_raw_file_is_refused_not_decoded_as_its_preview(make):
    with pytest.raises(InputError, match=r"^DSC_0001.NEF: a camera raw file \(NEF, DNG, CR2, ARW"):
        decode_image(make(), "DSC_0001.NEF")


def test_a_tethered_camera_delivering_a_raw_file_pauses_with_one_line():
    from lps_gui.camera.gphoto2_camera import decode

    with pytest.raises(HardwareError, match=r"^camera gphoto2:: DSC_0001.NEF: a camera raw file .*, then resume$"):
        decode(bad_images.nef_like(), "camera gphoto2:: DSC_0001.NEF")


# ------------------------------------------------------------------ lost data: one guard for every path written
def _lps(args, capsys) -> tuple[int, str]:
    from lps_gui.cli import main
    code = main([str(a) for a in args])
    err = capsys.readouterr().err.strip().splitlines()
    return code, err[-1] if err else ""


def _snapshot(folder) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _estimated(folder, capsys):
    assert _lps(["estimate", folder], capsys)[0] == 0
    return next(p for p in (folder / "results").iterdir() if p.is_dir())


@pytest.mark.parametrize("name", ["session.json", "captures.jsonl", "corners.vnl"])
def test_simulate_write_rig_never_replaces_a_session_file(point_session, capsys, name):
    before = _snapshot(point_session)
    code, err = _lps(["simulate", point_session / name, "--write-rig"], capsys)
    assert code == 2 and err.endswith(f"{point_session / name}: is a file of the session {point_session}; writing it "
                                      "would destroy the session's data: choose a name outside the session's own files")
    assert _snapshot(point_session) == before


def test_simulate_write_rig_never_replaces_a_special_file(tmp_path, capsys):
    fifo = tmp_path / "fifo"  # stands for a device node (as root a rename over /dev/null replaces it): never tried here
    os.mkfifo(fifo)
    code, err = _lps(["simulate", fifo, "--write-rig"], capsys)
    assert code == 2 and f"{fifo}: exists and is not a regular file" in err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_simulate_intrinsics_set_into_an_existing_folder_is_refused(point_session, capsys):
    before = _snapshot(point_session)  # a session: board.json among its files
    code, err = _lps(["simulate", point_session, "--intrinsics-set"], capsys)
    assert code == 2 and err.endswith(f"simulate --intrinsics-set {point_session}: exists and is not an empty folder; "
                                      "give a new folder (nothing of another set or session is replaced)")
    assert _snapshot(point_session) == before


@pytest.mark.parametrize("option", ["--out", "--yaml", "--cameramodel", "--report"])
def test_intrinsics_outputs_naming_an_input_are_refused_before_calibrating(tmp_path, capsys, option):
    board = tmp_path / "board.json"
    board.write_text('{"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}')
    view = tmp_path / "view.png"
    cv2.imwrite(str(view), np.full((24, 32), 128, np.uint8))
    for target in (board, view):
        args = ["intrinsics", view, "--board", board, "--workers", "1"]
        args += [option, target] if option == "--out" else ["--out", tmp_path / "i.json", option, target]
        code, err = _lps(args, capsys)
        assert code == 2 and f"{option} {target}: is one of this command's inputs" in err
    assert board.read_text().startswith('{"type": "chessboard"') and cv2.imread(str(view)).shape[:2] == (24, 32)


def test_detect_images_out_never_replaces_another_sessions_corners(point_session, tmp_path, capsys):
    board = tmp_path / "board.json"
    board.write_text('{"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}')
    view = tmp_path / "view.png"
    cv2.imwrite(str(view), np.full((24, 32), 128, np.uint8))
    before = _snapshot(point_session)
    for out in (point_session, point_session / "corners.vnl"):
        code, err = _lps(["detect", view, "--board", board, "--out", out, "--workers", "1"], capsys)
        assert code == 2 and f"is a file of the session {point_session}" in err
    assert _snapshot(point_session) == before


def test_compensate_and_estimate_never_replace_a_history_copy(point_session, tmp_path, capsys):
    run = _estimated(point_session, capsys)
    before = _snapshot(point_session)
    for args in (["compensate", point_session, "--format", "csv", "--out", run / "positions.csv"],
                 ["estimate", point_session, "--out", run / "results.json"]):
        code, err = _lps(args, capsys)
        assert code == 2 and f"is a file of the session {point_session}" in err, err
    assert _snapshot(point_session) == before


def test_estimate_of_one_session_never_replaces_anothers_result_set(point_session, tmp_path, capsys):
    from lps_gui.core.truth.simulate import small_spec
    from lps_gui.sim.points import simulate_point_session

    other = tmp_path / "other"
    simulate_point_session(small_spec(seed=4, views=10, directions="+", runs=1), other)
    _estimated(point_session, capsys)
    before = _snapshot(point_session)
    for out in (point_session, point_session / "results.json"):
        code, err = _lps(["estimate", other, "--out", out], capsys)
        assert code == 2 and f"is a file of the session {point_session}" in err, err
    assert _snapshot(point_session) == before
    assert _lps(["estimate", point_session, "--out", point_session], capsys)[0] == 0  # its own: allowed as before


def test_a_journal_renaming_onto_session_json_is_not_replayed(point_session, tmp_path, capsys):
    _estimated(point_session, capsys)
    (point_session / ".file-set-commit.json").write_text(json.dumps({"renames": [["captures.jsonl", "session.json"]]}))
    session_json = (point_session / "session.json").read_bytes()
    code, _ = _lps(["compensate", point_session, "--format", "csv", "--out", tmp_path / "c.csv"], capsys)
    assert (point_session / "session.json").read_bytes() == session_json
    assert (point_session / "captures.jsonl").is_file() and code == 0


# ------------------------------------------------------------------ hangs
POOL_CHILD = """
import multiprocessing.resource_tracker as rt, os, sys, time
from lps_gui.camera.processes import worker_pool
if __name__ == "__main__":
    with worker_pool(2) as pool:
        busy = [pool.submit(time.sleep, 600) for _ in range(2)]
        while len(pool._processes) < 2:
            time.sleep(0.05)
        print(*pool._processes, rt._resource_tracker._pid, flush=True)
        busy[0].result()
"""


def _gone(pid: int) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return True
    return "\nState:\tZ" in status  # a zombie has ended; only its reaper is missing


def _status(pid: int) -> str:
    """What a process still running is (its name, state and parent): which of the three, or another one's reused pid."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except FileNotFoundError:
        return "gone"
    return "; ".join(ln for ln in lines if ln.split(":")[0] in ("Name", "State", "PPid"))


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL])
def test_detect_workers_and_the_resource_tracker_end_with_their_parent(tmp_path, signum):
    script = tmp_path / "pool_child.py"
    script.write_text(POOL_CHILD)
    # the child starts with the signal's default action: a run under `nohup` (SIGHUP ignored, and an ignored signal
    # stays ignored across exec) is a user's choice to outlive the hang-up, not what this test is about
    default = None if signum == signal.SIGKILL else lambda: signal.signal(signum, signal.SIG_DFL)
    child = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True, cwd=ROOT,
                             preexec_fn=default)
    try:
        pids = [int(p) for p in child.stdout.readline().split()]
        assert len(pids) == 3 and not any(_gone(p) for p in pids)
        child.send_signal(signum)
        child.wait(timeout=60)
        # a bounded wait (never a hang) for the kernel to deliver the death signal, and for a worker still starting
        # (a spawned interpreter asks for the signal in its initializer) to see its parent gone: generous, as a
        # loaded machine with the other xdist worker busy slows that start; a survivor is named with its state
        deadline = time.monotonic() + 120
        while not all(_gone(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert all(_gone(p) for p in pids), {p: _status(p) for p in pids if not _gone(p)}
    finally:
        child.kill()
        child.wait()


def _fifo_or_link(path: Path, kind: str, tmp_path: Path) -> None:
    path.unlink()
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "urandom":
        path.symlink_to("/dev/urandom")
    else:
        os.mkfifo(tmp_path / "outside-fifo")
        path.symlink_to(tmp_path / "outside-fifo")


@pytest.mark.parametrize("kind", ["fifo", "urandom", "outside-fifo"])
def test_detect_returns_when_an_image_became_a_fifo_or_a_link_to_one(imaged_session, tmp_path, capsys, kind):
    from lps_gui.io.session import Session

    assert _lps(["detect", imaged_session, "--workers", "1"], capsys)[0] == 0
    first = Session.open(imaged_session).records()[0]
    _fifo_or_link(imaged_session / first.file, kind, tmp_path)
    code, err = _lps(["detect", imaged_session, "--workers", "1"], capsys)  # returns: the view fails with its reason
    assert code == 3 and err.startswith("failed: images/000000.png: ") and "\n" not in err


def test_a_journal_that_is_a_fifo_blocks_no_command(point_session, capsys):
    os.mkfifo(point_session / ".file-set-commit.json")
    assert _lps(["estimate", point_session], capsys)[0] == 0
    assert _lps(["report", point_session, "--out", point_session / "r.pdf"], capsys)[0] in (0, 1)


# ------------------------------------------------------------------ internal errors: parse errors caught at the boundary
@pytest.mark.parametrize("name", ["session.json", "board.json", "results.json"])
def test_an_integer_over_4300_digits_is_one_line(point_session, capsys, name):
    _estimated(point_session, capsys)
    path = point_session / name
    path.write_text(path.read_text().replace("{", '{"huge": ' + "9" * 5000 + ", ", 1))
    view = point_session.parent / "view.png"
    cv2.imwrite(str(view), np.full((24, 32), 128, np.uint8))
    command = {"session.json": ["estimate", point_session],
               "board.json": ["detect", view, "--board", path, "--out", point_session.parent / "c.vnl"],
               "results.json": ["compensate", point_session, "--format", "csv", "--out", point_session.parent / "c.csv"]}
    code, err = _lps(command[name], capsys)
    assert code == 2 and "a number in it is out of range (Exceeds the limit (4300 digits)" in err, err


def test_a_duplicate_key_is_refused_not_silently_the_second(tmp_path, capsys):
    board = tmp_path / "board.json"
    board.write_text('{"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20, "square_mm": 25}')
    view = tmp_path / "view.png"
    cv2.imwrite(str(view), np.full((24, 32), 128, np.uint8))
    code, err = _lps(["detect", view, "--board", board, "--out", tmp_path / "c.vnl"], capsys)
    assert code == 2 and err.endswith(f"{board}: key 'square_mm' appears twice in one object (which one counts is a "
                                      "guess); keep one and fix or regenerate the board file")


# ------------------------------------------------------------------ outside the session
def test_images_linked_outside_are_not_tidied_or_replayed_there(point_session, tmp_path, capsys):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / ".x.999999-y.tmp").write_text("someone's file")
    (outside / "notes.txt").write_text("notes")
    (outside / ".file-set-commit.json").write_text(json.dumps({"renames": [["notes.txt", "gone.txt"]]}))
    for p in (point_session / "images").iterdir():
        p.unlink()
    (point_session / "images").rmdir()
    (point_session / "images").symlink_to(outside)
    before = _snapshot(outside)
    _lps(["estimate", point_session], capsys)
    assert _snapshot(outside) == before


def test_results_linked_outside_receive_no_history_run(point_session, tmp_path, capsys):
    outside = tmp_path / "outside"
    outside.mkdir()
    (point_session / "results").symlink_to(outside)
    code, err = _lps(["estimate", point_session], capsys)
    assert code == 2 and err.endswith(f"{point_session / 'results'}: is a symbolic link; a session's result history "
                                      "stays inside the session: remove the link (lps creates the folder)")
    assert not list(outside.iterdir())


def test_a_linked_latest_record_is_not_opened(point_session, tmp_path, capsys):
    _estimated(point_session, capsys)
    os.mkfifo(tmp_path / "outside-fifo")
    latest = point_session / "results" / "latest.json"
    latest.unlink()
    latest.symlink_to(tmp_path / "outside-fifo")  # opening it would block: never opened
    assert _lps(["estimate", point_session], capsys)[0] == 0


@pytest.mark.parametrize("key", ["truth", "asme_test"])
def test_a_session_json_entry_of_the_wrong_type_is_one_line(point_session, capsys, key):
    meta = json.loads((point_session / "session.json").read_text())
    meta[key] = "x"
    (point_session / "session.json").write_text(json.dumps(meta))
    code, err = _lps(["estimate", point_session], capsys)
    assert code == 2 and err.endswith(f"{point_session / 'session.json'}: {key} is str, not an object; fix or "
                                      "regenerate session.json")


def test_a_nul_byte_in_a_path_is_one_line(point_session, capsys):
    code, err = _lps(["estimate", point_session, "--intrinsics", "intr\x00.json"], capsys)
    assert code == 2 and err.endswith("argument intrinsics: holds a NUL byte, which no file name or setting can; "
                                      "check the command line")


def test_corners_vnl_a_folder_is_one_line(point_session, capsys):
    (point_session / "corners.vnl").unlink()
    (point_session / "corners.vnl").mkdir()
    code, err = _lps(["estimate", point_session], capsys)
    assert code == 2 and err.endswith(f"{point_session / 'corners.vnl'}: not a regular file; delete it and run "
                                      "`lps detect` again")


def test_an_outlier_k_that_flags_every_view_is_refused_as_an_option(point_session, capsys):
    from lps_gui.cli import main
    with pytest.raises(SystemExit) as exc:
        main(["estimate", str(point_session), "--outlier-k", "1e-300"])
    assert exc.value.code == 2 and "--outlier-k: must be at least 1" in capsys.readouterr().err


# ------------------------------------------------------------------ confident wrong answers
def _edit_corners(folder, edit):
    from dataclasses import replace

    from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl
    from lps_gui.io.session import Session

    table = read_corners_vnl(folder / "corners.vnl", Session.open(folder).board().n_corners)
    write_corners_vnl(folder / "corners.vnl", replace(table, corners_px=edit(table.corners_px.copy())))


def _reverse_view_3(c):
    c[3] = c[3][::-1]
    return c


@pytest.mark.parametrize("edit,says", [
    (_reverse_view_3, "view images/000003.png: corners in the reverse order of the other views"),
    (lambda c: c * 2.0, "view images/000000.png: corners reach (858, 598) px, outside the 640x480 image of the intrinsics"),
    (lambda c: c[..., ::-1].copy(), "view images/000000.png: corners mirrored (x and y swapped?)"),
], ids=["reversed", "scaled", "swapped"])
def test_corners_that_do_not_fit_the_board_or_the_intrinsics_are_refused_not_estimated(point_session, capsys, edit, says):
    _edit_corners(point_session, edit)
    code, err = _lps(["estimate", point_session], capsys)
    assert code == 2 and f"{point_session / 'corners.vnl'}: {says}" in err and "nothing estimated" in err
    assert not (point_session / "results.json").exists()


def test_an_empty_target_entry_is_refused_not_dropped():
    from lps_gui.capture.plans import parse_targets

    assert parse_targets("0, 1.5,3,") == (0.0, 1.5, 3.0)
    with pytest.raises(InputError, match=r"^--targets '1,2,,3': give comma-separated positions in mm, e.g. 0,1.5,3 "
                                         r"\(no empty entry\)$"):
        parse_targets("1,2,,3")


def test_a_covariance_with_a_negative_variance_is_refused(tmp_path):
    from lps_gui.core.geometry.camera_model import CameraIntrinsics
    from lps_gui.io.intrinsics_file import read_intrinsics, write_intrinsics

    cov = np.diag([1.0, 1.0, 0.5, 0.5, 1e-4, 1e-4, 1e-6, 1e-6, 1e-5])
    cov[0, 0] = -1.0
    intr = CameraIntrinsics.from_values((640, 480), 800.0, 800.0, 320.0, 240.0, dist=(0.0,) * 5)
    path = tmp_path / "i.json"
    write_intrinsics(path, intr)
    d = json.loads(path.read_text())
    d["covariance"] = cov.tolist()
    path.write_text(json.dumps(d))
    with pytest.raises(InputError, match="covariance must be finite and symmetric with no negative variance"):
        read_intrinsics(path)


def test_make_targets_refuses_squares_too_small_to_print(tmp_path, capsys):
    from lps_gui.cli import main
    with pytest.raises(SystemExit) as exc:
        main(["make-targets", str(tmp_path / "t"), "--square-mm", "1e-9"])
    assert exc.value.code == 2 and "--square-mm: must be at least 1" in capsys.readouterr().err
    assert not (tmp_path / "t").exists()


# ------------------------------------------------------------------ promises kept quietly
def test_opencv_decoder_warnings_do_not_reach_stderr(capfd):
    entries = [(257, 3, 1, 16), (256, 3, 1, 16), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1), (273, 4, 1, -1),
               (277, 3, 1, 1), (278, 3, 1, 16), (279, 4, 1, 256)]  # tags out of order: libtiff warns
    data = bad_images.tiff(entries, bytes(256))
    capfd.readouterr()
    assert decode_image(data, "unsorted.tif").shape == (16, 16)
    assert capfd.readouterr().err == ""


def test_a_corners_file_for_the_general_parser_over_32_mb_is_refused_unparsed(point_session, capsys):
    path = point_session / "corners.vnl"
    with open(path, "wb") as f:
        f.write(b"# filename x y level\r\n")
        f.truncate((32 << 20) + 1)  # sparse: no disk, no memory until something parses it
    code, err = _lps(["estimate", point_session], capsys)
    assert code == 2 and "not in the form `lps detect` writes (over the 34 MB this reader takes)" in err, err
