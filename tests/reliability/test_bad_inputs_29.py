"""Issue 29, items 1-15: an independent campaign's bad inputs, one table.

Every case builds its input in a fresh copy of an estimated session and runs
``lps`` in-process under an alarm (a hang fails instead of blocking; FIFO
cases would block in ``open``) and checks: a non-zero exit that is not the
"bug" status 1, a one-line error without traceback, and for the cases that
could destroy session data, the session's files byte for byte as before.
``CASES`` is also the table docs/reliability.md counts (``category`` column).
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from lps_gui.cli import main
TIMEOUT_S = 60


@dataclass(frozen=True)
class Case:
    """One bad input: ``build(ctx)`` prepares it and returns the argv; ``codes`` the acceptable exits."""

    id: str
    item: int
    category: str
    build: Callable[["Ctx"], list[str]]
    codes: tuple[int, ...] = (2,)
    says: str = ""  # a word the error line must contain (case-insensitive)
    unchanged: tuple[str, ...] = ()  # session files that must keep their bytes ("*" = every file of S)
    isolated: bool = False  # run as a memory-capped subprocess (the case reads /dev/zero or gigabytes when unfixed)


@dataclass
class Ctx:
    tmp: Path
    S: Path  # estimated 1-D point session
    P: Path  # estimated planar point session
    B: Path  # another estimated 1-D session
    extra: dict = field(default_factory=dict)


class _Timeout(BaseException):
    """Not an Exception: main()'s bug handler must not swallow it."""


def run_lps(argv: list[str], timeout: int = TIMEOUT_S) -> int:
    def on_alarm(*_a):
        raise _Timeout(f"lps {' '.join(argv)} still running after {timeout} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(timeout)
    try:
        return main(argv)
    except SystemExit as exc:  # argparse refused an option
        return int(exc.code or 0)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


MEMORY_CAP = 3 << 30


def run_lps_isolated(argv: list[str], timeout: int = TIMEOUT_S) -> tuple[int, str]:
    """``lps argv`` in a subprocess with its address space capped: a case that reads without limit fails, not the host."""
    import resource
    import subprocess
    import sys

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))

    code = "import sys\nfrom lps_gui.cli import main\nsys.exit(main(sys.argv[1:]))"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    try:
        proc = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=timeout,
                              preexec_fn=cap, env=env, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return -1, f"lps {' '.join(argv)}: still running after {timeout} s"
    return proc.returncode, proc.stderr


def snapshot(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.is_symlink() and p.name != ".lock":
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


# ----------------------------------------------------------------------------- sessions
@pytest.fixture(scope="module")
def _sessions(tmp_path_factory):
    base = tmp_path_factory.mktemp("bad29")
    S, P, B = base / "S", base / "P", base / "B"
    assert main(["simulate", "--points", str(S)]) == 0
    assert main(["estimate", str(S)]) == 0
    assert main(["simulate", "--points", "--seed", "5", "--stops", "7", str(B)]) == 0
    assert main(["estimate", str(B)]) == 0
    assert main(["simulate", "--planar", "--points", "--preset", "small-planar", str(P)]) == 0
    assert main(["estimate", str(P)]) in (0, 4)
    return S, P, B


@pytest.fixture()
def ctx(_sessions, tmp_path):
    S, P, B = (tmp_path / p.name for p in _sessions)
    for src, dst in zip(_sessions, (S, P, B)):
        shutil.copytree(src, dst, symlinks=True)
    return Ctx(tmp_path, S, P, B)


def _meta(folder: Path) -> dict:
    return json.loads((folder / "session.json").read_text())


def _set_meta(folder: Path, **changes) -> None:
    meta = _meta(folder)
    meta.update(changes)
    (folder / "session.json").write_text(json.dumps(meta))


def _edit_results(folder: Path, edit: Callable[[dict], None]) -> None:
    res = json.loads((folder / "results.json").read_text())
    edit(res)
    (folder / "results.json").write_text(json.dumps(res))


def _edit_captures(folder: Path, line: int, **changes) -> None:
    lines = (folder / "captures.jsonl").read_text().splitlines()
    d = json.loads(lines[line])
    d.update(changes)
    lines[line] = json.dumps(d)
    (folder / "captures.jsonl").write_text("\n".join(lines) + "\n")


def _fifo(path: Path) -> Path:
    if path.exists() or path.is_symlink():
        path.unlink()
    os.mkfifo(path)
    return path


def _symlink(path: Path, target: Path | str) -> Path:
    if path.exists() or path.is_symlink():
        path.unlink()
    path.symlink_to(target)
    return path


def _outside_intrinsics(c: Ctx) -> Path:
    """The session's intrinsics as a file outside it (what a hostile session.json would name)."""
    outside = c.tmp / "outside"
    outside.mkdir(exist_ok=True)
    (outside / "intr.json").write_text(json.dumps(_meta(c.S)["intrinsics"]))
    return outside / "intr.json"


def _planar_meta(c: Ctx, axes) -> list[str]:
    meta = _meta(c.P)
    meta["plan"]["axes"] = axes
    (c.P / "session.json").write_text(json.dumps(meta))
    return ["estimate", str(c.P)]


def _corner_value(c: Ctx, value: str) -> list[str]:
    lines = (c.S / "corners.vnl").read_text().splitlines()
    i = next(i for i, line in enumerate(lines) if line and not line.startswith("#") and line.split()[1] != "-")
    parts = lines[i].split()
    parts[1] = value
    lines[i] = " ".join(parts)
    (c.S / "corners.vnl").write_text("\n".join(lines) + "\n")
    return ["estimate", str(c.S)]


def _tiff_ifd_at_end(path: Path, w: int = 12000, h: int = 12000) -> Path:
    """A little-endian TIFF whose IFD follows the image data (as OpenCV writes it), declaring w x h."""
    data = b"\0" * 70000  # past the 64 KB a header check reads
    ifd_offset = 8 + len(data)
    entries = [(256, 4, 1, w), (257, 4, 1, h), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1),
               (273, 4, 1, 8), (277, 3, 1, 1), (278, 4, 1, h), (279, 4, 1, len(data))]
    ifd = struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", *e) for e in entries) + struct.pack("<I", 0)
    path.write_bytes(b"II*\0" + struct.pack("<I", ifd_offset) + data + ifd)
    return path


def _board_json(c: Ctx) -> Path:
    (c.tmp / "board.json").write_text(json.dumps(_meta(c.S)["board"]))
    return c.tmp / "board.json"


def _another_sessions_results(c: Ctx) -> None:
    shutil.copy(c.B / "results.json", c.S / "results.json")


def _replay_session(c: Ctx, file: str) -> list[str]:
    """A replay folder whose captures.jsonl names ``file``."""
    rep = c.tmp / "replay"
    (rep / "images").mkdir(parents=True)
    (rep / "captures.jsonl").write_text(json.dumps({"index": 0, "run": 0, "direction": "+", "target_mm": 0.0,
                                                     "reported_mm": 0.0, "file": file, "sha256": None,
                                                     "time": 0.0}) + "\n")
    return ["capture", "--stage", "sim", "--camera", str(rep), "--board", str(_board_json(c)),
            "--out", str(c.tmp / "N"), "--stop", "2", "--step", "2"]


def _mixed_size_intrinsics_set(c: Ctx) -> list[str]:
    """An intrinsics set of 8 views, three of them shrunk to 320x240 (another camera or a resized copy)."""
    import cv2

    folder = c.tmp / "I"
    assert main(["simulate", "--intrinsics-set", "--views", "8", str(folder)]) == 0
    for name in ("view_001.png", "view_004.png", "view_006.png"):
        image = cv2.imread(str(folder / name), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(str(folder / name), cv2.resize(image, (320, 240), interpolation=cv2.INTER_AREA))
    return ["intrinsics", str(folder), "--board", str(folder / "board.json"), "--out", str(c.tmp / "i.json"), "--workers", "1"]


CASES: list[Case] = [
    # ---------------------------------------------------------------- 1-4: wrong results with exit 0
    Case("hybrid grid window 0", 1, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--grid-window-mm", "0"],
         says="grid-window-mm", unchanged=("*",)),
    Case("hybrid grid resolution 0", 1, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--grid-resolution-mm", "0"],
         says="grid-resolution-mm"),
    Case("hybrid grid resolution -1", 1, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--grid-resolution-mm", "-1"],
         says="grid-resolution-mm"),
    Case("hybrid grid window 1e308", 1, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--grid-window-mm", "1e308"],
         says="grid-window-mm", isolated=True),
    Case("hybrid grid of 1e12 points", 1, "wrong result",
         lambda c: ["estimate", str(c.S), "--method", "hybrid", "--grid-window-mm", "50", "--grid-resolution-mm", "1e-10"],
         says="grid", isolated=True),
    Case("intrinsics of images of two sizes", 2, "wrong result", _mixed_size_intrinsics_set, says="sizes"),
    Case("outlier-k nan", 3, "wrong result", lambda c: ["estimate", str(c.S), "--outlier-k", "nan"], says="outlier-k"),
    Case("outlier-k inf", 3, "wrong result", lambda c: ["estimate", str(c.S), "--outlier-k", "inf"], says="outlier-k"),
    Case("threshold-px nan", 3, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--threshold-px", "nan"],
         says="threshold-px"),
    Case("threshold-px -1", 3, "wrong result", lambda c: ["estimate", str(c.S), "--method", "hybrid", "--threshold-px", "-1"],
         says="threshold-px"),
    Case("report: results.json without positions", 3, "wrong result",
         lambda c: (_edit_results(c.S, lambda r: r.update(positions=[])), ["report", str(c.S)])[1], says="results.json"),
    Case("report: NaN measured positions", 3, "wrong result",
         lambda c: (_edit_results(c.S, lambda r: [p.update(measured_mm=float("nan")) for p in r["positions"]]),
                    ["report", str(c.S)])[1], says="results.json"),
    Case("report: 1e308 deviations", 3, "wrong result",
         lambda c: (_edit_results(c.S, lambda r: [p.update(deviation_um=1e308) for p in r["positions"]]),
                    ["report", str(c.S)])[1], says="results.json"),
    Case("compensate: results.json of another session", 4, "wrong result",
         lambda c: (_another_sessions_results(c), ["compensate", str(c.S), "--format", "csv", "--out", str(c.tmp / "t.csv")])[1],
         says="another session"),
    Case("export: results.json of another session", 4, "wrong result",
         lambda c: (_another_sessions_results(c), ["export", str(c.S), "--format", "csv", "--out", str(c.tmp / "x")])[1],
         says="another session"),
    Case("compare: results.json of another session", 4, "wrong result",
         lambda c: (_another_sessions_results(c), ["compare", str(c.S), str(c.B), "--out", str(c.tmp / "c.pdf")])[1],
         says="another session"),
    Case("compare: a 1-D and a planar session", 4, "wrong result",
         lambda c: ["compare", str(c.S), str(c.P), "--out", str(c.tmp / "c.pdf")], says="planar"),
    # ---------------------------------------------------------------- 5: --out naming session data
    Case("compensate --out S/captures.jsonl", 5, "data destroyed",
         lambda c: ["compensate", str(c.S), "--format", "linuxcnc", "--out", str(c.S / "captures.jsonl")],
         says="session", unchanged=("*",)),
    Case("compensate --out S/results.json", 5, "data destroyed",
         lambda c: ["compensate", str(c.S), "--format", "csv", "--out", str(c.S / "results.json")],
         says="session", unchanged=("*",)),
    Case("compensate --out S/session.json", 5, "data destroyed",
         lambda c: ["compensate", str(c.S), "--format", "csv", "--out", str(c.S / "session.json")],
         says="session", unchanged=("*",)),
    Case("compensate --out a FIFO", 5, "data destroyed",
         lambda c: ["compensate", str(c.S), "--format", "csv", "--out", str(_fifo(c.tmp / "pipe.csv"))],
         says="regular"),
    Case("report --out S/corners.vnl", 5, "data destroyed",
         lambda c: ["report", str(c.S), "--out", str(c.S / "corners.vnl")], unchanged=("*",)),
    Case("estimate --out S/corners.vnl", 5, "data destroyed",
         lambda c: ["estimate", str(c.S), "--out", str(c.S / "session.json")], says="session", unchanged=("*",)),
    # ---------------------------------------------------------------- 8: reads outside the session
    Case("session.json intrinsics absolute", 8, "read outside",
         lambda c: (_set_meta(c.S, intrinsics=str(_outside_intrinsics(c))), ["estimate", str(c.S)])[1], says="outside"),
    Case("session.json intrinsics ../", 8, "read outside",
         lambda c: (_outside_intrinsics(c), _set_meta(c.S, intrinsics="../outside/intr.json"), ["estimate", str(c.S)])[2],
         says="outside"),
    Case("session.json intrinsics a symlink", 8, "read outside",
         lambda c: (_symlink(c.S / "intr.json", _outside_intrinsics(c)), _set_meta(c.S, intrinsics="intr.json"),
                    ["estimate", str(c.S)])[2], says="symbolic link"),
    Case("symlinked session.json (estimate)", 8, "read outside",
         lambda c: (shutil.move(c.S / "session.json", c.tmp / "elsewhere.json"), _symlink(c.S / "session.json", c.tmp / "elsewhere.json"),
                    ["estimate", str(c.S)])[2], says="symbolic link"),
    Case("symlinked session.json (report)", 8, "read outside",
         lambda c: (shutil.move(c.S / "session.json", c.tmp / "elsewhere.json"), _symlink(c.S / "session.json", c.tmp / "elsewhere.json"),
                    ["report", str(c.S), "--out", str(c.tmp / "r.pdf")])[2], says="symbolic link"),
    Case("corners.vnl -> /dev/zero", 8, "read outside",
         lambda c: (_symlink(c.S / "corners.vnl", "/dev/zero"), ["estimate", str(c.S)])[1], says="corners.vnl", isolated=True),
    Case("truth.jsonl -> /dev/zero", 8, "read outside",
         lambda c: (_symlink(c.S / "truth.jsonl", "/dev/zero"), ["estimate", str(c.S)])[1], says="truth.jsonl", isolated=True),
    Case("replay camera names ../../outside/secret.png", 8, "read outside",
         lambda c: _replay_session(c, "../../outside/secret.png"), says="outside"),
    Case("replay camera names /dev/zero", 8, "read outside", lambda c: _replay_session(c, "/dev/zero"), says="outside", isolated=True),
    # ---------------------------------------------------------------- 9: hangs
    Case("FIFO session.json (estimate)", 9, "hang", lambda c: (_fifo(c.S / "session.json"), ["estimate", str(c.S)])[1],
         says="regular"),
    Case("FIFO session.json (report)", 9, "hang",
         lambda c: (_fifo(c.S / "session.json"), ["report", str(c.S), "--out", str(c.tmp / "r.pdf")])[1], says="regular"),
    Case("FIFO corners.vnl", 9, "hang", lambda c: (_fifo(c.S / "corners.vnl"), ["estimate", str(c.S)])[1], says="regular"),
    Case("FIFO --intrinsics", 9, "hang", lambda c: ["estimate", str(c.S), "--intrinsics", str(_fifo(c.tmp / "i.json"))],
         says="regular"),
    Case("FIFO --intrinsics yaml", 9, "hang", lambda c: ["estimate", str(c.S), "--intrinsics", str(_fifo(c.tmp / "i.yaml"))],
         says="regular"),
    Case("capture --stage emulator --time-scale 0", 9, "hang",
         lambda c: ["capture", "--stage", "emulator", "--camera", "sim", "--out", str(c.tmp / "N"), "--stop", "4",
                    "--step", "2", "--time-scale", "0"], says="time-scale"),
    # ---------------------------------------------------------------- 10: TIFF whose IFD follows the data
    Case("12000x12000 TIFF, IFD at the end (detect)", 10, "oversized",
         lambda c: ["detect", str(_tiff_ifd_at_end(c.tmp / "big.tif")), "--board", str(_board_json(c)), "--workers", "1",
                    "--out", str(c.tmp / "k.vnl")], codes=(2, 3), says="Mpx", isolated=True),
    Case("12000x12000 TIFF, IFD at the end (intrinsics)", 10, "oversized",
         lambda c: ["intrinsics", str(_tiff_ifd_at_end(c.tmp / "big.tif")), "--board", str(_board_json(c)), "--workers", "1",
                    "--out", str(c.tmp / "i.json")], codes=(2, 3), says="Mpx", isolated=True),
    # ---------------------------------------------------------------- 11: internal errors on session files
    Case("truth axis_mm holding 'a'", 11, "internal error",
         lambda c: (_set_meta(c.S, truth={**_meta(c.S)["truth"], "axis_mm": ["a"] * 30}), ["estimate", str(c.S)])[1],
         says="truth"),
    Case("garbage intrinsics YAML", 11, "internal error",
         lambda c: ((c.tmp / "intr.yaml").write_text("%YAML:1.0\n---\ncamera_matrix: [[[ \x01\n"),
                    ["estimate", str(c.S), "--intrinsics", str(c.tmp / "intr.yaml")])[1], says="intr.yaml"),
    Case("planar plan.axes 'XY'", 11, "internal error", lambda c: _planar_meta(c, "XY"), says="axes"),
    Case("planar plan.axes [X, Y, Z]", 11, "internal error", lambda c: _planar_meta(c, ["X", "Y", "Z"]), says="axes"),
    Case("planar plan.axes [X, X]", 11, "internal error", lambda c: _planar_meta(c, ["X", "X"]), says="axes"),
    Case("target_mm 1e308", 11, "internal error",
         lambda c: (_edit_captures(c.S, 1, target_mm=1e308), ["estimate", str(c.S)])[1], says="target_mm"),
    Case("target_mm [1, 2] in a 1-D session", 11, "internal error",
         lambda c: (_edit_captures(c.S, 1, target_mm=[1, 2]), ["estimate", str(c.S)])[1], says="target_mm"),
    Case("corner coordinate 1e308", 11, "internal error", lambda c: _corner_value(c, "1e308"), says="corners.vnl"),
    Case("captures.jsonl a folder", 11, "internal error",
         lambda c: ((c.S / "captures.jsonl").unlink(), (c.S / "captures.jsonl").mkdir(), ["estimate", str(c.S)])[2],
         says="captures.jsonl"),
    Case("binary truth.jsonl", 11, "internal error",
         lambda c: ((c.S / "truth.jsonl").write_bytes(bytes(range(256)) * 8),
                    ["estimate", str(c.S)])[1], says="truth.jsonl"),
    Case("planar results parameters 'x' (report)", 11, "internal error",
         lambda c: (_edit_results(c.P, lambda r: r.update(parameters="x")), ["report", str(c.P), "--out", str(c.tmp / "r.pdf")])[1],
         says="results.json"),
    # ---------------------------------------------------------------- 12: output paths
    Case("export --out an existing file", 12, "output path",
         lambda c: ((c.tmp / "f").write_text("keep"), ["export", str(c.S), "--format", "csv", "--out", str(c.tmp / "f")])[1],
         says="--out"),
    Case("export --out under /proc", 12, "output path",
         lambda c: ["export", str(c.S), "--format", "csv", "--out", "/proc/lps-calib-test/x"], says="--out"),
    Case("simulate into an existing file", 12, "output path",
         lambda c: ((c.tmp / "f").write_text("keep"), ["simulate", "--points", str(c.tmp / "f")])[1], says="folder"),
    Case("demo --out an existing file", 12, "output path",
         lambda c: ((c.tmp / "f").write_text("keep"), ["demo", "--quick", "--out", str(c.tmp / "f")])[1], says="--out"),
    # ---------------------------------------------------------------- 13: oversized inputs
    Case("1.2 GB sparse corners.vnl", 13, "oversized",
         lambda c: (os.truncate(c.S / "corners.vnl", 1_200_000_000), ["estimate", str(c.S)])[1], says="corners.vnl", isolated=True),
    Case("plan-rig --inner-corners 10000x10000", 13, "oversized",
         lambda c: ["plan-rig", "--focal-mm", "8", "--pixel-um", "3.45", "--image", "2448x2048", "--inner-corners", "10000x10000",
                    "--square-mm", "1", "--distance-mm", "300", "--stop", "100", "--step", "10"], says="inner"),
    # ---------------------------------------------------------------- 14: absurd options
    Case("capture --intrinsics-views 0", 14, "option",
         lambda c: ["capture", "--camera", "sim", "--out", str(c.tmp / "N"), "--intrinsics-views", "0"], says="intrinsics-views"),
    Case("capture --pitch -1", 14, "option",
         lambda c: ["capture", "--camera", "sim", "--stage", "sim", "--out", str(c.tmp / "N"), "--iso-plan", "--pitch", "-1"],
         says="pitch"),
    Case("simulate --stops 0", 14, "option", lambda c: ["simulate", "--points", str(c.tmp / "N"), "--stops", "0"], says="stops"),
    Case("simulate --runs 0", 14, "option", lambda c: ["simulate", "--points", str(c.tmp / "N"), "--runs", "0"], says="runs"),
    Case("simulate --missing-fraction 1.5", 14, "option",
         lambda c: ["simulate", "--points", str(c.tmp / "N"), "--missing-fraction", "1.5"], says="missing-fraction"),
    Case("simulate --views 0", 14, "option", lambda c: ["simulate", "--intrinsics-set", str(c.tmp / "N"), "--views", "0"],
         says="views"),
    Case("simulate --squareness-urad 1e308", 14, "option",
         lambda c: ["simulate", "--planar", "--points", str(c.tmp / "N"), "--squareness-urad", "1e308"], says="squareness"),
    Case("detect --workers 0", 14, "option", lambda c: ["detect", str(c.S), "--workers", "0"], says="workers"),
    Case("detect --workers -3", 14, "option", lambda c: ["detect", str(c.S), "--workers", "-3"], says="workers"),
    Case("intrinsics --workers 0", 14, "option",
         lambda c: ["intrinsics", str(c.tmp), "--board", str(_board_json(c)), "--workers", "0"], says="workers"),
    Case("demo --seed -1", 14, "option", lambda c: ["demo", "--quick", "--seed", "-1", "--out", str(c.tmp / "d")], says="seed"),
    Case("capture --time-scale -1", 14, "option",
         lambda c: ["capture", "--stage", "emulator", "--camera", "sim", "--out", str(c.tmp / "N"), "--time-scale", "-1"],
         says="time-scale"),
    Case("capture --runs 0", 14, "option",
         lambda c: ["capture", "--camera", "sim", "--out", str(c.tmp / "N"), "--runs", "0"], says="runs"),
    Case("capture --frames 0", 14, "option",
         lambda c: ["capture", "--camera", "sim", "--out", str(c.tmp / "N"), "--frames", "0"], says="frames"),
    Case("estimate --outlier-k 0", 14, "option", lambda c: ["estimate", str(c.S), "--outlier-k", "0"], says="outlier-k"),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_a_one_line_error(case: Case, ctx: Ctx, capsys):
    argv = case.build(ctx)
    watched = snapshot(ctx.S) if case.unchanged else {}
    capsys.readouterr()
    if case.isolated:
        code, err = run_lps_isolated(argv)
    else:
        code = run_lps(argv)
        err = capsys.readouterr().err
    lines = [line for line in err.strip().splitlines() if line.strip() and "[#" not in line and "[-" not in line]
    assert code in case.codes, f"exit {code}, expected {case.codes}: {err[-600:]}"
    assert "Traceback" not in err and "internal error" not in err, err[-600:]
    assert lines and "error" in lines[-1], err[-600:]
    assert case.says.lower() in lines[-1].lower(), lines[-1]
    if case.unchanged:
        now = snapshot(ctx.S)
        if case.unchanged == ("*",):
            assert now == watched
        else:
            assert {k: now.get(k) for k in case.unchanged} == {k: watched.get(k) for k in case.unchanged}


def category_counts() -> dict[str, int]:
    """Cases per category (docs/reliability.md quotes these)."""
    out: dict[str, int] = {}
    for c in CASES:
        out[c.category] = out.get(c.category, 0) + 1
    return out


__all__ = ["CASES", "Case", "Ctx", "category_counts", "run_lps", "snapshot", "np"]


DOC_ROWS = ("wrong result", "data destroyed", "read outside", "hang", "oversized", "internal error", "output path", "option")


def test_docs_reliability_counts_match_this_table():
    """docs/reliability.md's issue-29 table states this table's counts (its 'handled now' column is what this suite asserts)."""
    import re

    doc = (Path(__file__).parents[2] / "docs" / "reliability.md").read_text()
    block = doc.split("<!-- issue29:start -->")[1].split("<!-- issue29:end -->")[0]
    rows = [line.split("|")[1:-1] for line in block.strip().splitlines()[2:]]
    counts = category_counts()
    for category, row in zip(DOC_ROWS, rows):
        cases, now = int(row[1]), int(row[3])
        assert cases == now == counts[category], (category, row)
    total = rows[len(DOC_ROWS)]
    assert int(re.sub(r"\D", "", total[1])) == int(re.sub(r"\D", "", total[3])) == len(CASES) == sum(counts.values())
    assert set(counts) == set(DOC_ROWS)
