"""The fault-and-bad-input campaign of issue 17, over the ``lps`` command line.

Every case builds what it needs in a fresh folder, runs ``lps`` (in this
process through ``lps_gui.cli.main``, or as a subprocess where a kill or a
second process is the point), and checks what was promised: the exit code,
one error line naming the problem (never "internal error"), and that
nothing already captured or computed was lost or changed. Disk-full and
read-only cases use a small tmpfs when this runs as root and mounting works;
otherwise they are reported as skipped.

    python tools/campaign.py                 # every case, markdown table on stdout
    python tools/campaign.py --fast          # the quick subset (tests run it)
    python tools/campaign.py --write docs/reliability.md
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
LPS = [sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main(sys.argv[1:]))"]
BOARD = {"type": "chessboard", "inner_corners": [9, 6], "square_mm": 20}


@dataclass
class Outcome:
    ok: bool
    result: str


@dataclass
class Case:
    kind: str  # "input" or "fault"
    name: str
    expected: str
    run: Callable[[Path], Outcome]
    fast: bool = True


CASES: list[Case] = []


def case(kind: str, name: str, expected: str, fast: bool = True):
    def add(fn: Callable[[Path], Outcome]) -> Callable[[Path], Outcome]:
        CASES.append(Case(kind, name, expected, fn, fast))
        return fn
    return add


# ------------------------------------------------------------------ helpers
def lps(*args: str) -> tuple[int, str, str]:
    """Run ``lps args`` in this process: (exit code, stdout, stderr)."""
    from lps_gui.cli import main
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:  # argparse
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


def last_line(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1] if lines else ""


def clean_error(code: int, err: str, want_code: int = 2, needle: str = "") -> Outcome:
    """Exit ``want_code`` with one error line (after any progress bars) holding ``needle``."""
    line = last_line(err)
    ok = code == want_code and ": error: " in line and "internal error" not in err and needle.lower() in line.lower()
    return Outcome(ok, f"exit {code}: {line[:160]}")


def digest(folder: Path, skip: tuple[str, ...] = ()) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.is_symlink() and p.name not in skip:
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def point_session(tmp: Path, name: str = "s") -> Path:
    from lps_gui.core.truth.simulate import small_spec
    from lps_gui.sim.points import simulate_point_session

    simulate_point_session(small_spec(seed=3, views=10, directions="+", runs=1), tmp / name)
    return tmp / name


_IMAGED: dict[str, Path] = {}


def imaged_session(tmp: Path) -> Path:
    """A copy of one small captured session with 320x240 images (6 frames, made once per run)."""
    if "s" not in _IMAGED:
        base = Path(tempfile.mkdtemp(prefix="lps-campaign-imaged-"))
        code, _, err = lps("capture", "--out", base / "s", "--start", "0", "--stop", "10", "--step", "2",
                           "--settle", "0", "--overshoot", "1")
        assert code == 0, err
        _IMAGED["s"] = base / "s"
    shutil.copytree(_IMAGED["s"], tmp / "imaged")
    return tmp / "imaged"


def edit_records(session: Path, fn: Callable[[list[dict]], None]) -> None:
    path = session / "captures.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()]
    fn(records)
    path.write_text("".join(json.dumps(r) + "\n" for r in records))


def huge_png(path: Path, w: int = 30000, h: int = 30000) -> Path:
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    chunk = lambda kind, data: struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 1000)) + chunk(b"IEND", b""))
    return path


def write_board(tmp: Path, board: dict | None = None) -> Path:
    (tmp / "board.json").write_text(json.dumps(board or BOARD))
    return tmp / "board.json"


def intrinsics_file(tmp: Path, **change) -> Path:
    d = {"image_size": [640, 480], "camera_matrix": [[600, 0, 320], [0, 600, 240], [0, 0, 1]],
         "dist": [0.0, 0.0, 0.0, 0.0, 0.0]}
    d.update(change)
    (tmp / "intr.json").write_text(json.dumps(d))
    return tmp / "intr.json"


class Tmpfs:
    """A small tmpfs at ``folder`` (root only); ``fill()`` leaves ``keep`` bytes free; ``readonly()`` remounts it ro."""

    def __init__(self, folder: Path, size: str = "2m"):
        self.folder, self.size, self.mounted = folder, size, False

    def __enter__(self) -> "Tmpfs | None":
        self.folder.mkdir(parents=True, exist_ok=True)
        if os.geteuid() != 0:
            return None
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={self.size}", "tmpfs", str(self.folder)], capture_output=True)
        self.mounted = r.returncode == 0
        return self if self.mounted else None

    def fill(self, keep: int = 8192) -> None:
        try:
            with open(self.folder / ".filler", "wb") as f:
                while True:
                    f.write(b"\0" * 4096)
                    f.flush()
        except OSError:
            pass
        size = (self.folder / ".filler").stat().st_size
        os.truncate(self.folder / ".filler", max(0, size - keep))

    def readonly(self) -> None:
        subprocess.run(["mount", "-o", "remount,ro", str(self.folder)], check=True)

    def __exit__(self, *exc) -> None:
        if self.mounted:
            subprocess.run(["umount", "-l", str(self.folder)], check=False)


SKIP = Outcome(True, "skipped: needs root to mount a tmpfs")


# ------------------------------------------------------------------ bad inputs: session files
@case("input", "binary session.json", "exit 2, names session.json")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    (s / "session.json").write_bytes(bytes(range(256)) * 4)
    return clean_error(*lps("estimate", s)[::2], needle="session.json")


@case("input", "session.json nested 200000 deep", "exit 2, names session.json")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    (s / "session.json").write_text("[" * 200000 + "]" * 200000)
    return clean_error(*lps("estimate", s)[::2], needle="session.json")


@case("input", "binary captures.jsonl line", "exit 2, names the line")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    lines = (s / "captures.jsonl").read_bytes().split(b"\n")
    lines[2] = bytes(range(1, 200))
    (s / "captures.jsonl").write_bytes(b"\n".join(lines))
    return clean_error(*lps("estimate", s)[::2], needle="line 3")


@case("input", "index 1e30", "exit 2, names field and line")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    edit_records(s, lambda r: r[1].update(index=1e30))
    return clean_error(*lps("estimate", s)[::2], needle="'index'")


@case("input", "NaN target_mm", "exit 2, names field and line")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    edit_records(s, lambda r: r[1].update(target_mm=float("nan")))
    return clean_error(*lps("estimate", s)[::2], needle="'target_mm'")


@case("input", "time as ISO 8601", "accepted: exit 0")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    edit_records(s, lambda r: [x.update(time="2026-11-30T10:00:00Z") for x in r])
    code, out, err = lps("estimate", s)
    return Outcome(code == 0, f"exit {code}: {last_line(err or out)[:120]}")


@case("input", "time 'yesterday'", "exit 2, names 'time' and line")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    edit_records(s, lambda r: r[2].update(time="yesterday"))
    return clean_error(*lps("estimate", s)[::2], needle="line 3")


@case("input", "duplicated capture index", "exit 2, names both lines")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    edit_records(s, lambda r: r.append(dict(r[1])))
    return clean_error(*lps("estimate", s)[::2], needle="repeats index")


@case("input", "file ../outside.png", "exit 2, outside the session folder")
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    edit_records(s, lambda r: r[1].update(file="../outside.png"))
    return clean_error(*lps("detect", s, "--workers", "1")[::2], needle="outside the session folder")


@case("input", "file /dev/zero", "exit 2, outside the session folder")
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    edit_records(s, lambda r: r[1].update(file="/dev/zero"))
    return clean_error(*lps("detect", s, "--workers", "1")[::2], needle="outside the session folder")


@case("input", "image symlinked to /dev/zero", "exit 3, that view failed: symbolic link")
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    (s / "images" / "000001.png").unlink()
    (s / "images" / "000001.png").symlink_to("/dev/zero")
    code, _, err = lps("detect", s, "--workers", "1")
    return Outcome(code == 3 and "symbolic link" in err, f"exit {code}: {[l for l in err.splitlines() if l.startswith('failed:')][:1]}")


@case("input", "symlinked captures.jsonl", "exit 2, its target untouched")
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    target = tmp / "precious"
    target.write_bytes((s / "captures.jsonl").read_bytes()[:-30])
    before = target.read_bytes()
    (s / "captures.jsonl").unlink()
    (s / "captures.jsonl").symlink_to(target)
    code, _, err = lps("capture", "--resume", s)
    out = clean_error(code, err, needle="symbolic link")
    return Outcome(out.ok and target.read_bytes() == before, out.result)


@case("input", "stage URL in session.json on --resume", "exit 2, nothing opened")
def _(tmp: Path) -> Outcome:
    from lps_gui.core.planning.plan import Plan
    from lps_gui.io.board_file import board_from_dict
    from lps_gui.io.session import Session

    Session.create(tmp / "s", board_from_dict(BOARD), Plan(targets_mm=(0.0, 1.0)), camera={"spec": "0"},
                   stage={"spec": "grbl:socket://203.0.113.9:23"})
    return clean_error(*lps("capture", "--resume", tmp / "s")[::2], needle="give --stage and --camera")


@case("input", "image replaced after detection", "re-detected; estimate before it: exit 2")
def _(tmp: Path) -> Outcome:
    import cv2
    import numpy as np

    s = imaged_session(tmp)
    lps("detect", s, "--workers", "1")
    rec = json.loads((s / "captures.jsonl").read_text().splitlines()[2])
    img = np.roll(cv2.imread(str(s / rec["file"]), cv2.IMREAD_GRAYSCALE), 5, axis=1)
    data = cv2.imencode(".png", img)[1].tobytes()
    (s / rec["file"]).write_bytes(data)
    edit_records(s, lambda r: r[2].update(sha256=hashlib.sha256(data).hexdigest()))
    code_e, _, err_e = lps("estimate", s)
    code, out, _ = lps("detect", s, "--workers", "1")
    return Outcome(code_e == 2 and "older image" in err_e and "kept 5" in out,
                   f"estimate exit {code_e}; detect: {last_line(out)[:90]}")


# ------------------------------------------------------------------ bad inputs: board, intrinsics, images
@case("input", "inner_corners 1e9", "exit 2, names inner_corners")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    meta = json.loads((s / "session.json").read_text())
    meta["board"]["inner_corners"] = [1e9, 6]
    (s / "session.json").write_text(json.dumps(meta))
    return clean_error(*lps("estimate", s)[::2], needle="inner_corners")


@case("input", "inner_corners 9.5", "exit 2 (not truncated to 9)")
def _(tmp: Path) -> Outcome:
    b = write_board(tmp, {**BOARD, "inner_corners": [9.5, 6]})
    huge = tmp / "x.png"
    import cv2
    import numpy as np

    cv2.imwrite(str(huge), np.zeros((40, 40), np.uint8))
    return clean_error(*lps("detect", huge, "--board", b)[::2], needle="inner_corners")


@case("input", "fx 1e300", "exit 2, names the focal length")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    f = intrinsics_file(tmp, camera_matrix=[[1e300, 0, 320], [0, 1e300, 240], [0, 0, 1]])
    return clean_error(*lps("estimate", s, "--intrinsics", f)[::2], needle="focal")


@case("input", "std \"abc\"", "exit 2, names std")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    return clean_error(*lps("estimate", s, "--intrinsics", intrinsics_file(tmp, std={"fx": "abc"}))[::2], needle="std")


@case("input", "ragged covariance", "exit 2, names covariance")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    cov = [[0.0] * 9 for _ in range(8)] + [[0.0] * 4]
    return clean_error(*lps("estimate", s, "--intrinsics", intrinsics_file(tmp, covariance=cov))[::2], needle="covariance")


@case("input", "image_size 0", "exit 2, names image_size")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    return clean_error(*lps("estimate", s, "--intrinsics", intrinsics_file(tmp, image_size=[0, 480]))[::2], needle="image_size")


@case("input", "a single distortion coefficient", "exit 2, names dist")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    return clean_error(*lps("estimate", s, "--intrinsics", intrinsics_file(tmp, dist=[0.1]))[::2], needle="dist")


@case("input", "30000x30000 PNG to detect --board", "exit 2 before decoding")
def _(tmp: Path) -> Outcome:
    return clean_error(*lps("detect", huge_png(tmp / "big.png"), "--board", write_board(tmp), "--workers", "1")[::2],
                       needle="30000x30000")


@case("input", "30000x30000 PNG to intrinsics", "exit 2, says 30000x30000")
def _(tmp: Path) -> Outcome:
    return clean_error(*lps("intrinsics", huge_png(tmp / "big.png"), "--board", write_board(tmp), "--workers", "1",
                            "--out", tmp / "i.json")[::2], needle="30000x30000")


@case("input", "four copies of one image to intrinsics", "exit 2, distinct views")
def _(tmp: Path) -> Outcome:
    code, _, err = lps("simulate", tmp / "set", "--intrinsics-set", "--views", "3", "--seed", "1")
    if code:
        return Outcome(False, f"simulate failed: {last_line(err)}")
    first = sorted((tmp / "set").rglob("*.png"))[0]
    (tmp / "c").mkdir()
    for k in range(4):
        shutil.copy(first, tmp / "c" / f"{k}.png")
    board = next((tmp / "set").rglob("board.json"), None) or write_board(tmp, json.loads((tmp / "set" / "session.json").read_text())["board"])
    return clean_error(*lps("intrinsics", tmp / "c", "--board", board, "--workers", "1", "--out", tmp / "i.json")[::2],
                       needle="distinct")


@case("input", "corners of one view on one row", "exit 2, names the view")
def _(tmp: Path) -> Outcome:
    from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl

    s = point_session(tmp)
    t = read_corners_vnl(s / "corners.vnl", 54)
    t.corners_px[3, :, 1] = t.corners_px[3, 0, 1]
    write_corners_vnl(s / "corners.vnl", t)
    return clean_error(*lps("estimate", s)[::2], needle="on one line")


@case("input", "corners scaled x1e12", "exit 2 (corners refused) or 4, loud")
def _(tmp: Path) -> Outcome:
    from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl

    s = point_session(tmp)
    t = read_corners_vnl(s / "corners.vnl", 54)
    t.corners_px = t.corners_px * 1e12
    write_corners_vnl(s / "corners.vnl", t)
    code, _, err = lps("estimate", s)
    return Outcome(code in (2, 4) and "internal error" not in err and ("warning" in err or "error" in err),
                   f"exit {code}: {last_line(err)[:140]}")


# ------------------------------------------------------------------ bad inputs: plans and switches
for _args, _needle in (
    (["--stop", "1e9", "--step", "1"], "over the limit"),
    (["--stop", "10", "--step", "1e-6"], "below"),
    (["--targets", "0,1e-9"], "one position"),
    (["--stop", "10", "--step", "1", "--overshoot", "-1"], "overshoot"),
    (["--stop", "10", "--step", "1", "--settle", "-1"], "settle"),
    (["--targets", "0,nan,2"], "finite"),
    (["--stop", "10", "--step", "1", "--feed", "0"], "feed"),
    (["--stop", "10", "--step", "1", "--encode", ".jpg"], "lossless"),
):
    def _plan_case(tmp: Path, args=_args, needle=_needle) -> Outcome:
        out = clean_error(*lps("capture", "--out", tmp / "s", "--start", "0", *args)[::2], needle=needle)
        return Outcome(out.ok and not (tmp / "s" / "captures.jsonl").exists(), out.result)

    CASES.append(Case("input", "capture " + " ".join(_args), f"exit 2 ({_needle}), nothing captured", _plan_case))


@case("input", "estimate a paper rig whose board leaves the view (1500 stops)", "exit 2 at once, says the board left the view")
def _(tmp: Path) -> Outcome:
    code, _, err = lps("simulate", tmp / "s", "--points", "--preset", "paper-rig", "--stops", "1500")
    if code != 0:
        return Outcome(False, f"simulate exit {code}: {last_line(err)}")
    return clean_error(*lps("estimate", tmp / "s")[::2], needle="leaves the camera's view")


@case("input", "simulate --noise-px -1", "exit 2")
def _(tmp: Path) -> Outcome:
    return clean_error(*lps("simulate", tmp / "s", "--points", "--noise-px", "-1")[::2], needle="noise")


@case("input", "rig description with noise_px < 0", "exit 2, names noise_px")
def _(tmp: Path) -> Outcome:
    lps("simulate", tmp / "rig.json", "--write-rig")
    rig = json.loads((tmp / "rig.json").read_text())
    rig["noise_px"] = -1
    (tmp / "rig.json").write_text(json.dumps(rig))
    return clean_error(*lps("simulate", tmp / "s", "--points", "--rig", tmp / "rig.json")[::2], needle="noise_px")


# ------------------------------------------------------------------ bad inputs: CLI as a new user
@case("input", "detect /nonexistent", "exit 2, not found")
def _(tmp: Path) -> Outcome:
    return clean_error(*lps("detect", tmp / "nonexistent")[::2], needle="not found")


@case("input", "detect --board b junk/ (no board in the images)", "exit 2, nothing written")
def _(tmp: Path) -> Outcome:
    import cv2
    import numpy as np

    (tmp / "junk").mkdir()
    cv2.imwrite(str(tmp / "junk" / "a.png"), np.full((60, 80), 128, np.uint8))
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        out = clean_error(*lps("detect", "--board", write_board(tmp), "junk", "--workers", "1")[::2], needle="found in none")
    finally:
        os.chdir(cwd)
    return Outcome(out.ok and not (tmp / "corners.vnl").exists(), out.result)


@case("input", "intrinsics on images without a board", "exit 2, board not found")
def _(tmp: Path) -> Outcome:
    import cv2
    import numpy as np

    for k in range(3):
        cv2.imwrite(str(tmp / f"{k}.png"), np.full((60, 80), 100 + k, np.uint8))
    return clean_error(*lps("intrinsics", *[tmp / f"{k}.png" for k in range(3)], "--board", write_board(tmp),
                            "--workers", "1", "--out", tmp / "i.json")[::2], needle="board was found in none")


@case("input", "report on a non-session folder", "exit 2, not a session folder")
def _(tmp: Path) -> Outcome:
    (tmp / "x").mkdir()
    return clean_error(*lps("report", tmp / "x")[::2], needle="not a session folder")


@case("input", "report --out existing_dir", "report.pdf inside, no .tmp left", fast=False)
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    lps("estimate", s)
    (tmp / "d").mkdir()
    code, out, err = lps("report", s, "--out", tmp / "d")
    names = sorted(p.name for p in (tmp / "d").iterdir())
    return Outcome(code == 0 and names == ["report.pdf"], f"exit {code}: {names}")


@case("input", "estimate --out est.json", "a file est.json (CSVs beside it)")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    code, _, err = lps("estimate", s, "--out", tmp / "est.json")
    return Outcome(code == 0 and (tmp / "est.json").is_file(), f"exit {code}: est.json is_file={(tmp / 'est.json').is_file()}")


@case("input", "detect SESSION --no-track", "honoured (no tracking)")
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    code, out, _ = lps("detect", s, "--workers", "1", "--no-track")
    return Outcome(code == 0 and "tracked 0" in out, f"exit {code}: {last_line(out)[:100]}")


# ------------------------------------------------------------------ faults
def full_disk(tmp: Path, size: str, keep: int, make: Callable[[Path], Path], command: Callable[[Path], tuple],
              needle: str) -> Outcome:
    """Make a session on a small tmpfs, fill the disk, run ``command(session)``: one error line, every file unchanged."""
    with Tmpfs(tmp / "disk", size) as fs:
        if fs is None:
            return SKIP
        s = make(fs.folder)
        before = digest(s)
        fs.fill(keep=keep)
        code, _, err = lps(*command(s))
        out = clean_error(code, err, needle=needle)
        return Outcome(out.ok and digest(s) == before, out.result)


def estimated_session(folder: Path, with_report: bool = False) -> Path:
    s = point_session(folder)
    lps("estimate", s)
    if with_report:
        (s / "report.pdf").write_bytes(b"%PDF-1.4 old\n%%EOF\n")
    return s


@case("fault", "report on a full disk", "exit 2, old report.pdf kept", fast=False)
def _(tmp: Path) -> Outcome:
    return full_disk(tmp, "1m", 8192, lambda f: estimated_session(f, True), lambda s: ("report", s), "report.pdf")


@case("fault", "estimate on a full disk", "exit 2, old results set kept")
def _(tmp: Path) -> Outcome:
    return full_disk(tmp, "2m", 4096, estimated_session, lambda s: ("estimate", s, "--method", "pnp"), "space")


@case("fault", "detect on a full disk", "exit 2, captures kept")
def _(tmp: Path) -> Outcome:
    return full_disk(tmp, "4m", 2048, imaged_session, lambda s: ("detect", s, "--workers", "1"), "space")


@case("fault", "simulate on a full disk", "exit 2, one line", fast=False)
def _(tmp: Path) -> Outcome:
    with Tmpfs(tmp / "disk", "1m") as fs:
        if fs is None:
            return SKIP
        fs.fill(keep=4096)
        return clean_error(*lps("simulate", fs.folder / "s", "--points")[::2])


@case("fault", "capture on a full disk", "stops before any move or pauses; every listed frame intact", fast=False)
def _(tmp: Path) -> Outcome:
    with Tmpfs(tmp / "disk", "1m") as fs:
        if fs is None:
            return SKIP
        code, _, err = lps("capture", "--out", fs.folder / "s", "--start", "0", "--stop", "38", "--step", "2", "--settle", "0")
        from lps_gui.io.session import Session

        intact = True
        try:
            for r in Session.open(fs.folder / "s").records():
                intact &= hashlib.sha256((fs.folder / "s" / r.file).read_bytes()).hexdigest() == r.sha256
        except Exception as exc:  # noqa: BLE001 - any failure to read back is a finding
            return Outcome(False, f"exit {code}; session unreadable: {exc}")
        return Outcome(code in (2, 3) and intact and "internal error" not in err, f"exit {code}: {last_line(err)[:120]}")


for _cmd in ("estimate", "detect", "resume"):
    def _ro_case(tmp: Path, cmd=_cmd) -> Outcome:
        with Tmpfs(tmp / "disk", "4m") as fs:
            if fs is None:
                return SKIP
            s = imaged_session(fs.folder) if cmd != "estimate" else point_session(fs.folder)
            if cmd == "resume":
                lines = (s / "captures.jsonl").read_text().splitlines()
                (s / "captures.jsonl").write_text("\n".join(lines[:3]) + "\n")
            before = digest(s)
            fs.readonly()
            args = {"estimate": ("estimate", s), "detect": ("detect", s, "--workers", "1"),
                    "resume": ("capture", "--resume", s)}[cmd]
            code, _, err = lps(*args)
            out = clean_error(code, err)
            return Outcome(out.ok and digest(s) == before, out.result)

    CASES.append(Case("fault", f"{_cmd} in a read-only session", "exit 2, one line, nothing changed", _ro_case))


@case("fault", "estimate while a capture holds the session", "exit 2, names the holder")
def _(tmp: Path) -> Outcome:
    s = point_session(tmp)
    hold = subprocess.Popen([sys.executable, "-c", "import sys; from lps_gui.io.session_lock import SessionLock\n"
                             "with SessionLock(sys.argv[1], 'lps capture --resume S'):\n print('held', flush=True); sys.stdin.read()",
                             str(s)], cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        hold.stdout.readline()
        return clean_error(*lps("estimate", s)[::2], needle=f"pid {hold.pid}")
    finally:
        hold.communicate("", timeout=30)


@case("fault", "two `lps capture --resume S` at once", "one resumes, the other exit 2; no duplicate", fast=False)
def _(tmp: Path) -> Outcome:
    s = imaged_session(tmp)
    lines = (s / "captures.jsonl").read_text().splitlines()
    (s / "captures.jsonl").write_text(lines[0] + "\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [subprocess.Popen([*LPS, "capture", "--resume", str(s), "--real-time"], cwd=ROOT, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    codes = sorted(p.wait(timeout=300) for p in procs)
    from lps_gui.io.session import Session

    try:
        indices = [r.index for r in Session.open(s).records()]
    except Exception as exc:  # noqa: BLE001
        return Outcome(False, f"exits {codes}; {exc}")
    if codes == [0, 0]:  # the first finished before the second started: also fine if nothing is duplicated
        return Outcome(len(indices) == len(set(indices)) == 6, f"exits {codes} (one after the other), {len(indices)} records")
    return Outcome(codes == [0, 2] and len(indices) == len(set(indices)) == 6, f"exits {codes}, {len(indices)} records")


@case("fault", "SIGKILL during capture, then resume", "resume completes; every frame intact", fast=False)
def _(tmp: Path) -> Outcome:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    s = tmp / "s"
    p = subprocess.Popen([*LPS, "capture", "--out", str(s), "--start", "0", "--stop", "38", "--step", "2", "--settle", "0.05",
                          "--real-time"], cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        path = s / "captures.jsonl"
        if path.exists() and len(path.read_bytes().splitlines()) >= 5:
            break
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)
    p.wait()
    r = subprocess.run([*LPS, "capture", "--resume", str(s)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    from lps_gui.io.session import Session

    recs = Session.open(s).records()
    intact = all(hashlib.sha256((s / x.file).read_bytes()).hexdigest() == x.sha256 for x in recs)
    return Outcome(r.returncode == 0 and intact and len(recs) == 20 and len({x.index for x in recs}) == 20,
                   f"resume exit {r.returncode}, {len(recs)} records, intact {intact}")


@case("fault", "stage stops 0.5 mm short", "capture pauses (exit 3), frame not listed")
def _(tmp: Path) -> Outcome:
    from lps_gui.capture import engine
    real = engine.CaptureEngine._go_to

    def short(self, stop):
        real(self, stop)
        if stop.target_mm > 5:
            self._reported_mm = stop.target_mm - 0.5
            engine.check_reached(stop.target_mm, self._reported_mm, self.position_tolerance_mm)

    engine.CaptureEngine._go_to = short
    try:
        code, _, err = lps("capture", "--out", tmp / "s", "--start", "0", "--stop", "10", "--step", "2", "--settle", "0")
    finally:
        engine.CaptureEngine._go_to = real
    n = len((tmp / "s" / "captures.jsonl").read_text().splitlines())
    return Outcome(code == 3 and "-500.0 um" in err and n == 3, f"exit {code}, {n} listed: {last_line(err)[:100]}")


# ------------------------------------------------------------------ running
def run_cases(fast: bool, only: str | None = None) -> list[tuple[Case, Outcome]]:
    rows = []
    for c in CASES:
        if (fast and not c.fast) or (only and only not in c.name):
            continue
        with tempfile.TemporaryDirectory(prefix="lps-campaign-") as d:
            try:
                outcome = c.run(Path(d))
            except Exception as exc:  # noqa: BLE001 - a crash of the case is a failed case
                outcome = Outcome(False, f"case crashed: {type(exc).__name__}: {str(exc)[:120]}")
        rows.append((c, outcome))
        print(f"{'ok ' if outcome.ok else 'BAD'} {c.kind:5} {c.name}: {outcome.result}", file=sys.stderr, flush=True)
    return rows


def table(rows: list[tuple[Case, Outcome]]) -> str:
    def cell(text: str) -> str:
        import re

        text = re.sub(r"/tmp/lps-campaign-[^/ ]+/", "", text)  # each case's own temp folder
        return text.replace("|", "\\|").replace("\n", " ")

    inputs = [(c, o) for c, o in rows if c.kind == "input"]
    faults = [(c, o) for c, o in rows if c.kind == "fault"]
    skipped = sum(o.result.startswith("skipped") for _, o in rows)
    lines = [
        f"Bad inputs handled cleanly: **{sum(o.ok for _, o in inputs)} of {len(inputs)}**; "
        f"faults survived with nothing lost: **{sum(o.ok and not o.result.startswith('skipped') for _, o in faults)} of "
        f"{len(faults)}**" + (f" ({skipped} skipped)" if skipped else "") + ".",
        "",
        "| kind | case | expected | result | |",
        "|---|---|---|---|---|",
    ]
    for c, o in rows:
        mark = "skip" if o.result.startswith("skipped") else ("ok" if o.ok else "**FAIL**")
        lines.append(f"| {c.kind} | {cell(c.name)} | {cell(c.expected)} | {cell(o.result)} | {mark} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="only the quick cases")
    ap.add_argument("--only", help="only the cases whose name contains this text")
    ap.add_argument("--write", type=Path, help="replace the table between the markers in this markdown file")
    args = ap.parse_args(argv)
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    rows = run_cases(args.fast, args.only)
    text = table(rows)
    if args.write:
        doc = args.write.read_text()
        start, end = "<!-- campaign:start -->", "<!-- campaign:end -->"
        head, _, rest = doc.partition(start)
        _, _, tail = rest.partition(end)
        args.write.write_text(f"{head}{start}\n{text}{end}{tail}")
    else:
        print(text)
    return 0 if all(o.ok for _, o in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
