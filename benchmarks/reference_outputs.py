"""Byte-identical outputs across a refactor (issue 34): run the reference set, then compare two runs.

    python benchmarks/reference_outputs.py run OUT [--code DIR]   # DIR: a checkout whose lps_gui to run (default this one)
    python benchmarks/reference_outputs.py compare BEFORE AFTER   # exit 1 on any difference

Run both at the same OUT and move each away before the next (mv OUT BEFORE): session.json holds its folder, so its
hash, printed on page 1 in the identification block that is centred on its widest line, differs with the folder,
and with it that block's place and wrapping.

The reference set: the quick demo (a bidirectional line, its compensated as-left session and the as-found/as-left
comparison), planar, a row of targets, min-step, settling, two depths (points) and a stitched session. Compared:
every results.json, positions.csv and summary.csv (times, input hashes and the run's folder masked), and every PDF
page: its text lines and their places (masked alike) and everything else drawn (the content stream without its
text objects, and the images): what fixes the pixels. Every run reads one fixed time of day (a sitecustomize
beside the outputs): the masked times are then also the same width, so page 1 is laid out alike. The outputs are
not committed: keep BEFORE outside the tree.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parents[1]
DEMOS = {"line": [], "planar": ["--planar"], "row": ["--preset", "small-row"],
         "minstep": ["--test", "min-step"], "settling": ["--test", "settling"]}
VOLATILE = ("created", "timings_s", "sha256", "version")  # results.json keys that differ between any two runs
TIMESTAMP = re.compile(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}[+-]\d{4}")
HASH = re.compile(r"sha256\s+\S+")
STITCHED = """
import sys
sys.path.append({tests!r})  # after the checkout under test: its lps_gui first
from tests.pipeline.test_stitched_estimate import stitched_session
stitched_session(__import__('pathlib').Path({out!r}), 0)
"""


FIXED_CLOCK = """
# written by benchmarks/reference_outputs.py: every run's time.strftime reads one fixed time of day
import time as _time

_FIXED, _strftime = _time.localtime({epoch}), _time.strftime
_time.strftime = lambda fmt, t=None: _strftime(fmt, _FIXED if t is None else t)
"""
CLOCK_EPOCH = 1767268800  # 2026-01-01 12:00 UTC


def _clock_dir(out: Path) -> Path:
    """A folder with a sitecustomize that fixes time.strftime: the reports' times, masked in the comparison, are then
    also the same width, so a centred block (page 1's identification) is laid out and wrapped alike in every run."""
    folder = out / ".fixed-clock"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(FIXED_CLOCK.format(epoch=CLOCK_EPOCH))
    return folder


def _env(code: Path, out: Path) -> dict[str, str]:
    """The environment of a run: *code*'s lps_gui first on the path, then the fixed clock, Qt offscreen."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(code), str(_clock_dir(out))]), "QT_QPA_PLATFORM": "offscreen"}


def _lps(code: Path, args: list[str], log: Path) -> None:
    """Run the CLI of the checkout *code* (its lps_gui first on the path), its output into *log*."""
    env = _env(code, log.parent)
    with log.open("a") as f:
        f.write(f"$ lps {' '.join(args)}\n")
        f.flush()
        subprocess.run([sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main())", *args],
                       env=env, stdout=f, stderr=subprocess.STDOUT, check=False, timeout=3600, cwd=log.parent)


def run(out: Path, code: Path) -> None:
    """Write the reference set into *out* (one folder per run; each run's working folder, so that no checkout in the
    current folder shadows *code*)."""
    out = out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    log = out / "runs.log"
    for name, extra in DEMOS.items():
        _lps(code, ["demo", "--quick", "--out", str(out / name), *extra], log)
    two = out / "two-depth"
    _lps(code, ["simulate", "--points", "--preset", "paper-two-depth", str(two)], log)
    _lps(code, ["estimate", str(two)], log)
    _lps(code, ["report", str(two)], log)
    stitched = out / "stitched"
    subprocess.run([sys.executable, "-c", STITCHED.format(tests=str(HERE), out=str(stitched))], env=_env(code, out),
                   check=True, timeout=600, cwd=out)
    _lps(code, ["estimate", str(stitched)], log)
    _lps(code, ["report", str(stitched)], log)


def _mask(text: str, root: Path) -> str:
    """Text with the run's folder and the times of day masked (they differ between any two runs)."""
    return HASH.sub("sha256 <hash>", TIMESTAMP.sub("<time>", text.replace(str(root), "<out>")))


def _scrub(value: Any, root: Path) -> Any:
    """The JSON value with times, input hashes and the run's folder masked."""
    if isinstance(value, dict):
        return {_mask(k, root): "<scrubbed>" if k in VOLATILE else _scrub(v, root) for k, v in value.items()}
    if isinstance(value, list):
        return [_scrub(v, root) for v in value]
    if isinstance(value, str):
        return _mask(value, root)
    return value


def _csv(path: Path, root: Path) -> list[str]:
    """A CSV's lines with the run's folder and times masked."""
    return [_mask(line, root) for line in path.read_text().splitlines()]


def _pdf(path: Path, root: Path) -> list[tuple[Any, ...]]:
    """Per page: every text line with its place (times and folder masked) and a digest of everything else drawn
    (the content stream without its text objects, and the images): equal pages look the same."""
    from pdfminer.high_level import extract_pages
    from pdfminer.layout import LTTextContainer, LTTextLine
    from pypdf import PdfReader

    reader = PdfReader(path)
    pages = []
    for page, layout in zip(reader.pages, extract_pages(path)):
        h = hashlib.sha256()
        contents = page.get_contents()
        h.update(re.sub(rb"\bBT\b.*?\bET\b", b"", contents.get_data() if contents is not None else b"", flags=re.S))
        resources = page.get("/Resources") or {}
        xobjects = resources.get("/XObject") or {}
        for name in sorted(xobjects):
            h.update(name.encode() + xobjects[name].get_object().get_data())
        # x compared by _same_page: a centred block follows the width of its widest line, a masked time's digits
        lines = [(round(line.y0, 2), _mask(line.get_text(), root), round(line.x0, 1))
                 for box in layout if isinstance(box, LTTextContainer) for line in box if isinstance(line, LTTextLine)]
        pages.append((h.hexdigest(), sorted(lines)))  # pdfminer's grouping order follows the masked widths too
    return pages


def _same_page(p: tuple[Any, ...], q: tuple[Any, ...]) -> bool:
    """The same drawing and the same text lines at the same heights, each in place or all moved across together.

    Why the one shift: page 1's identification block is centred on its widest line, which holds the run's time;
    two runs of the same code (main against main) move the whole block sideways by up to 5 pt, every line alike.
    """
    if p[0] != q[0] or len(p[1]) != len(q[1]) or any(a[:2] != b[:2] for a, b in zip(p[1], q[1])):
        return False
    shifts = [b[2] - a[2] for a, b in zip(p[1], q[1]) if abs(b[2] - a[2]) > 0.15]
    return not shifts or max(shifts) - min(shifts) <= 0.3


def _files(root: Path) -> list[Path]:
    keep = ("results.json", "positions.csv", "summary.csv", ".pdf")
    return sorted(p.relative_to(root) for p in root.rglob("*")
                  if p.is_file() and p.name.endswith(keep) and "results" not in p.relative_to(root).parts[:-1])


def compare(before: Path, after: Path) -> int:
    """Print each differing file and return the number of differences."""
    a, b = _files(before), _files(after)
    bad = 0
    for missing in sorted(set(a) ^ set(b)):
        print(f"only in {'before' if missing in a else 'after'}: {missing}")
        bad += 1
    for rel in sorted(set(a) & set(b)):
        x, y = before / rel, after / rel
        if rel.suffix == ".json":
            same = _scrub(json.loads(x.read_text()), before) == _scrub(json.loads(y.read_text()), after)
        elif rel.suffix == ".csv":
            same = _csv(x, before) == _csv(y, after)
        else:
            px, py = _pdf(x, before), _pdf(y, after)
            same = len(px) == len(py) and all(_same_page(p, q) for p, q in zip(px, py))
            if not same:
                diff = [i + 1 for i, (p, q) in enumerate(zip(px, py)) if not _same_page(p, q)]
                print(f"  {rel}: pages {len(px)} / {len(py)}, differing pages {diff}")
        if not same:
            print(f"DIFFERS: {rel}")
            bad += 1
    print(f"{len(set(a) & set(b))} files compared, {bad} differences")
    return bad


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--code", type=Path, default=HERE)
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    args = parser.parse_args()
    if args.cmd == "run":
        run(args.out, args.code)
        return 0
    return 1 if compare(args.before, args.after) else 0


if __name__ == "__main__":
    sys.exit(main())
