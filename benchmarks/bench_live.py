"""Live results: from the last frame written to results.json, against a separate detect + estimate.

The simulated paper rig (400 stops 1 mm apart, rendered 1920x1080 images,
the stage moving and settling in real time) is captured by
`lps capture --preset paper-rig --real-time --live` as a child process (the
whole process: interpreter, imports, capture, live detection, running
estimates, final estimate). The latency is the time from the last capture
line (captures.jsonl's modification time) to results.json's; the goal is
under 3 s. The reference, in this process on the same session: a separate
`lps detect --force` (worker processes) + `lps estimate` (pipeline calls),
whose results must equal the live ones (1e-9 relative).

    .venv/bin/python benchmarks/bench_live.py [--dir /tmp/lps-bench-live] [--stops 400]

One run on a shared machine: the load average is printed with the numbers.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

LPS = [sys.executable, "-c", "import sys; from lps_gui.cli import main; sys.exit(main())"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", type=Path, default=Path("/tmp/lps-bench-live"))
    ap.add_argument("--stops", type=int, default=400)
    args = ap.parse_args()
    shutil.rmtree(args.dir, ignore_errors=True)
    args.dir.mkdir(parents=True)
    folder = args.dir / "live"
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores", flush=True)
    t0 = time.time()
    cmd = [*LPS, "capture", "--out", str(folder), "--preset", "paper-rig", "--real-time", "--live",
           "--stop", str(args.stops - 1)]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t_end = time.time()
    if proc.returncode != 0:
        raise SystemExit(f"lps capture failed ({proc.returncode}): {proc.stderr[-2000:]}")
    last_frame = (folder / "captures.jsonl").stat().st_mtime
    results_at = (folder / "results.json").stat().st_mtime
    n = sum(1 for _ in (folder / "captures.jsonl").open())
    flags = [line for line in proc.stderr.splitlines() if line.startswith("lps capture: frame")]
    print(f"capture of {n} frames (real-time stage, live): {t_end - t0:.1f} s wall; {len(flags)} live flag(s)")
    latency = results_at - last_frame
    print(f"last frame written -> results.json: {latency:.2f} s (goal < 3 s), whole process", flush=True)
    live_results = json.loads((folder / "results.json").read_text())
    live_corners = (folder / "corners.vnl").read_bytes()

    from lps_gui.pipeline.detect import detect_session
    from lps_gui.pipeline.estimate import estimate_session

    print(f"load average before the reference: {os.getloadavg()[0]:.2f}", flush=True)
    t1 = time.perf_counter()
    detect_session(folder, force=True)
    t2 = time.perf_counter()
    separate = estimate_session(folder)
    t3 = time.perf_counter()
    print(f"separate detect + estimate, this process: {t3 - t1:.2f} s (detect {t2 - t1:.2f} s, estimate {t3 - t2:.2f} s)")
    print(f"ratio live latency / separate detect+estimate: {latency / (t3 - t1):.3f}")
    same_corners = (folder / "corners.vnl").read_bytes() == live_corners
    a = np.array([p["measured_mm"] for p in live_results["positions"]], float)
    b = np.array([p["measured_mm"] for p in separate["positions"]], float)
    rel = float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))
    print(f"corners.vnl identical to lps detect's: {same_corners}; max relative position difference: {rel:.2e}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
