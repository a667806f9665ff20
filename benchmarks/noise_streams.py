"""Is a campaign cell's error a bias or its seeds' noise draw? Re-draw one kept gantry session's image noise.

The simulated camera seeds each grab's noise with ``default_rng([seed, capture index, 1])``
(:meth:`lps_gui.sim.rig.RigCamera.seed_capture`). This renders the kept session's true poses (board-plane
positions, the rig's nominal orientation) with that noise stream for other seeds, re-detects the corners
(``refine`` from the true projections, as the tracker ends), re-estimates with the true intrinsics and prints
the planar scale and squareness errors per stream. The session's own seed reproduces its images bit for bit,
so the spread over streams is what the seeds' noise alone does on those poses (docs/validation.md, "Planar
scale X: the +22 ppm (realism off) is the campaign's noise draw"). A realism-off flat-stage gantry only.

    .venv/bin/python benchmarks/noise_streams.py KEPT_FOLDER --streams 0,10,11 [--work /tmp/lps-noise-streams]

KEPT_FOLDER is one folder of ``benchmarks/honesty.py --keep`` (it holds ``session/``); about 12 s a stream.
"""
from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import cv2
import numpy as np

from lps_gui.camera.detection import refine, subpix_half_window
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.truth.simulate import nominal_planar_state, project_scene
from lps_gui.io.corners.vnl import read_corners_vnl, write_corners_vnl
from lps_gui.io.session import Session
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.session import spec_of_session


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kept", type=Path)
    ap.add_argument("--streams", default="0,10,11", help="noise seeds, comma separated")
    ap.add_argument("--work", type=Path, default=Path("/tmp/lps-noise-streams"))
    args = ap.parse_args()
    src = args.kept / "session"
    session = Session.open(src)
    spec = spec_of_session(session)
    truth = [json.loads(line) for line in (src / "truth.jsonl").read_text().splitlines()]
    captures = [json.loads(line) for line in (src / "captures.jsonl").read_text().splitlines()]
    state = nominal_planar_state(spec.rig, np.array([t["board_plane_mm"] for t in truth]))
    T = state.translations()
    true_px = project_scene(spec, np.repeat(state.R[None], len(T), axis=0), T)
    half_window = subpix_half_window(true_px[0], spec.rig.board)
    camera = session.meta.get("camera") or {}
    renderer = BoardRenderer(spec.rig.board, spec.rig.intrinsics, lighting=Lighting(blur_px=camera.get("blur_px", 1.2)),
                             noise_grey=camera.get("noise_grey", 2.0))
    errors = []
    for stream in (int(v) for v in args.streams.split(",")):
        images = [renderer.render(state.R, T[k], np.random.default_rng([stream, int(c["index"]), 1]))
                  for k, c in enumerate(captures)]
        if stream == spec.seed:
            same = np.array_equal(images[0], cv2.imread(str(src / captures[0]["file"]), cv2.IMREAD_GRAYSCALE))
            print(f"stream {stream} is the session's own: first image identical to the kept one: {same}")
        work = args.work / f"stream-{stream}"
        if work.exists():
            shutil.rmtree(work)
        shutil.copytree(src, work, ignore=shutil.ignore_patterns("images", "results"))
        meta = json.loads((work / "session.json").read_text())
        meta["intrinsics"]["camera_matrix"] = spec.rig.intrinsics.camera_matrix.tolist()
        meta["intrinsics"]["dist"] = [float(v) for v in spec.rig.intrinsics.dist]
        (work / "session.json").write_text(json.dumps(meta))
        table = read_corners_vnl(work / "corners.vnl", true_px.shape[1])
        found = np.array([refine(img, true_px[k], half_window) for k, img in enumerate(images)])
        table.corners_px[:] = np.where(np.isfinite(table.corners_px), found, np.nan)
        write_corners_vnl(work / "corners.vnl", table)
        tc = estimate_session(work)["truth_comparison"]
        errors.append([tc["scale_x_error_ppm"], tc["scale_y_error_ppm"], tc["squareness_error_urad"]])
        print(f"stream {stream}: scale X error {errors[-1][0]:+.1f} ppm, scale Y {errors[-1][1]:+.1f} ppm, "
              f"squareness {errors[-1][2]:+.1f} urad", flush=True)
    e = np.array(errors)
    sd = e.std(axis=0, ddof=1) if len(e) > 1 else np.zeros(3)
    print(f"{len(e)} streams: mean (sd) scale X {e[:, 0].mean():+.1f} ({sd[0]:.1f}) ppm, "
          f"scale Y {e[:, 1].mean():+.1f} ({sd[1]:.1f}) ppm, squareness {e[:, 2].mean():+.1f} ({sd[2]:.1f}) urad")


if __name__ == "__main__":
    main()
