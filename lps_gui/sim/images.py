"""Rendered-image sessions with known truth: `lps simulate OUT` and `lps simulate --intrinsics-set OUT`.

The session simulator renders exactly the poses of the point simulator
(:func:`core.simulate.true_views`: same seed, same truth, same replaced and
bumped views) into a session folder written like a real capture: each image
atomically, then its captures.jsonl line. Rendering runs in worker processes
(each builds its per-pixel rays once) while the main process writes, in
capture order, with a bounded number of frames in flight.
"""
from __future__ import annotations

import logging
import os
import time
from concurrent.futures import Future
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np

from lps_gui.camera.processes import worker_pool
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics, project_board
from lps_gui.core.geometry.rotation import exp_so3
from lps_gui.core.geometry.target_rig import TargetLayout
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.truth.simulate import (
    SimulationSpec,
    frame_since_move_s,
    placement_poses,
    true_views,
)
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.board_file import write_board
from lps_gui.io.intrinsics_file import write_intrinsics
from lps_gui.io.jsonfile import write_json
from lps_gui.io.session import CaptureRecord, Session
from lps_gui.sim.session import write_simulated_session

_RENDERERS: dict[Any, Any] = {}
Scene = Board | TargetLayout  # one board, or a row / constellation of targets (SPEC 13)


def _scene_key(scene: Scene) -> Any:
    if isinstance(scene, Board):
        return scene
    return (scene.targets, scene.Q.tobytes(), scene.p.tobytes())


def _renderer(board: Scene, intrinsics: CameraIntrinsics, lighting: Lighting, noise_grey: float, lens: Any = None
              ) -> Any:
    """One renderer per process and camera: the per-pixel rays take seconds to build."""
    key = (_scene_key(board), intrinsics.image_size, intrinsics.vector().tobytes(), intrinsics.higher.tobytes(), lighting,
           noise_grey, lens)
    if key not in _RENDERERS:
        _RENDERERS.clear()
        if isinstance(board, Board):
            _RENDERERS[key] = BoardRenderer(board, intrinsics, lighting=lighting, noise_grey=noise_grey, lens=lens)
        else:
            from lps_gui.camera.render_targets import TargetsRenderer

            _RENDERERS[key] = TargetsRenderer(board, intrinsics, lighting=lighting, noise_grey=noise_grey, lens=lens)
    return _RENDERERS[key]


def render_encoded(
    board: Scene,
    intrinsics: CameraIntrinsics,
    lighting: Lighting,
    noise_grey: float,
    poses: Sequence[tuple[np.ndarray, np.ndarray, int]],
    image_ext: str,
    lens: Any = None,
) -> list[bytes]:
    """Render and encode frames; each pose carries its own noise seed so any split gives the same images.
    ``lens``: the true lens's terms beyond ``intrinsics`` (the simulator's realism)."""
    import cv2

    cv2.setNumThreads(1)
    r = _renderer(board, intrinsics, lighting, noise_grey, lens)
    params = [cv2.IMWRITE_PNG_COMPRESSION, 1] if image_ext.lower() == ".png" else []
    out = []
    for R, t, seed in poses:
        img = r.render(R, t, np.random.default_rng(seed))
        ok, buf = cv2.imencode(image_ext, img, params)
        if not ok:
            raise InputError(f"simulate: cannot encode images as {image_ext!r}; use .png")
        out.append(buf.tobytes())
    return out


def _render_stream(
    board: Scene,
    intrinsics: CameraIntrinsics,
    lighting: Lighting,
    noise_grey: float,
    poses: list[tuple[np.ndarray, np.ndarray, int]],
    image_ext: str,
    workers: int,
    chunk: int = 8,
    lens: Any = None,
) -> Iterator[bytes]:
    """Encoded frames in order; at most ``2 * workers`` chunks in flight."""
    chunks = [poses[i : i + chunk] for i in range(0, len(poses), chunk)]
    if workers <= 1 or len(chunks) <= 1:
        for c in chunks:
            yield from render_encoded(board, intrinsics, lighting, noise_grey, c, image_ext, lens)
        return
    from concurrent.futures.process import BrokenProcessPool

    next_out = 0  # first chunk not yet yielded
    try:
        with worker_pool(workers) as pool:  # workers end with this process
            queue: list[Future] = []
            next_chunk = 0
            try:
                while queue or next_chunk < len(chunks):
                    while next_chunk < len(chunks) and len(queue) < 2 * workers:
                        queue.append(pool.submit(render_encoded, board, intrinsics, lighting, noise_grey, chunks[next_chunk], image_ext,
                                                 lens))
                        next_chunk += 1
                    frames = queue.pop(0).result()
                    next_out += 1
                    yield from frames
            finally:
                for f in queue:
                    f.cancel()
    except BrokenProcessPool:  # e.g. a calling script without the __main__ guard: render here
        logging.getLogger(__name__).warning("worker processes failed to start; rendering in this process")
        for c in chunks[next_out:]:
            yield from render_encoded(board, intrinsics, lighting, noise_grey, c, image_ext, lens)


def simulate_image_session(
    spec: SimulationSpec,
    out: Path,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    image_ext: str = ".png",
    intrinsics: CameraIntrinsics | None = None,
    noise_grey: float = 2.0,
    lighting: Lighting | None = None,
    workers: int | None = None,
) -> Session:
    """Render every view of ``spec`` into a new session folder ``out``.

    Parameters
    ----------
    spec : the simulated experiment; truth equals the point simulator's.
    out : a folder without a session in it.
    intrinsics : embedded in session.json (default: the rig's true ones;
        pass a calibrated CameraIntrinsics to test with realistic errors).
    noise_grey : Gaussian image noise sigma, grey levels.
    Returns the session; cancelling keeps every image already listed.
    """
    out = Path(out)
    lighting = lighting or Lighting()
    realism = spec.camera_realism()  # the simulator's realism switches (issue 35): {} when off
    lens, scene = realism.pop("lens", None), realism.pop("printed", None)
    lighting = replace(lighting, **realism)
    rng = np.random.default_rng(spec.seed)
    stops, R, t, truth = true_views(spec, rng)
    K = len(stops)
    src = np.arange(K)
    for i in spec.replaced_views:  # the image of another position, as if files were swapped
        src[i] = (i + spec.replaced_offset) % K
    truth = {**truth, "image_noise_grey": noise_grey, "lighting": asdict(lighting), "renderer": "exact-area"}
    rig = spec.rig
    session = write_simulated_session(
        out, spec, "images", intrinsics=intrinsics or rig.intrinsics,
        camera={"driver": "SimulatedCamera", "width": rig.intrinsics.image_size[0], "height": rig.intrinsics.image_size[1],
                "noise_grey": noise_grey, "blur_px": lighting.blur_px},
        stage={"driver": "SimulatedStage", "errors": rig.errors.to_dict()},
        truth=truth,
    )
    R, t = placement_poses(spec, stops, R, t)  # a stitched session: the board where it lay for the segment
    poses = [(R[j], t[j], spec.seed * 100003 + i) for i, j in enumerate(src)]
    workers = max(1, int(workers or os.cpu_count() or 1))
    progress(0, K, "rendering")
    t0 = time.time()
    scene = scene or (rig.board if spec.one_board else spec.layout)
    if spec.stitched:  # one board (its markers too: the targets renderer) seen from each placement's pose
        scene = TargetLayout((replace(spec.layout.targets[0], board=scene),), np.eye(3)[None], np.zeros((1, 3)))
    frames = _render_stream(scene, rig.intrinsics, lighting, noise_grey, poses, image_ext, workers if K > 16 else 1,
                            lens=lens)
    for stop, data in zip(stops, frames):
        if cancel is not None:
            cancel.check("image simulation")
        rel, sha = session.write_image(f"{stop.index:06d}{image_ext}", data)
        session.append(CaptureRecord(stop.index, stop.run, stop.direction, stop.target_mm, stop.target_mm, rel, sha,
                                     t0 + stop.index, stop.frame, since_move_s=frame_since_move_s(spec, stop.frame),
                                     segment=stop.segment))
        progress(stop.index + 1, K, rel)
    return session


def _look_at_pose(
    rng: np.random.Generator,
    board: Board,
    intrinsics: CameraIntrinsics,
    k: int,
    n_views: int,
    max_tilt_deg: float,
) -> tuple[np.ndarray, np.ndarray]:
    """A random pose: board tilted about an in-plane axis, centred somewhere in the image."""
    w, h = intrinsics.image_size
    phi = 2 * np.pi * k / n_views + rng.uniform(-0.3, 0.3)  # tilt directions spread around the circle
    tilt = np.deg2rad(rng.uniform(0.25, 1.0) * max_tilt_deg)
    R = exp_so3(np.array([np.cos(phi), np.sin(phi), 0.0]) * tilt) @ exp_so3(np.array([0.0, 0.0, rng.uniform(-0.3, 0.3)]))
    fill = rng.uniform(0.45, 0.95)  # fraction of the image the board spans
    bw, bh = (board.cols + 1) * board.square_mm, (board.rows + 1) * board.square_mm
    Z = min(intrinsics.fx * bw / (fill * w), intrinsics.fy * bh / (fill * h))
    target = np.array([rng.uniform(0.2, 0.8) * w, rng.uniform(0.2, 0.8) * h])
    ray = np.array([(target[0] - intrinsics.cx) / intrinsics.fx, (target[1] - intrinsics.cy) / intrinsics.fy, 1.0])
    t = Z * ray - R @ board.centre_mm()
    return R, t


def sample_intrinsics_poses(
    board: Board,
    intrinsics: CameraIntrinsics,
    n_views: int,
    rng: np.random.Generator,
    max_tilt_deg: float = 45.0,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Varied poses whose whole board (outer squares included) is in the image, near its edges."""
    w, h = intrinsics.image_size
    s = board.square_mm
    outline = np.array([[-s, -s, 0], [board.cols * s, -s, 0], [-s, board.rows * s, 0], [board.cols * s, board.rows * s, 0]])
    poses: list[tuple[np.ndarray, np.ndarray]] = []
    tries = 0
    while len(poses) < n_views:
        tries += 1
        if tries > 200 * n_views:
            raise InputError("simulate: cannot fit the board in the image at varied poses; use a smaller board")
        R, t = _look_at_pose(rng, board, intrinsics, len(poses), n_views, max_tilt_deg)
        uv = project_board(R, t, outline, intrinsics)
        if np.all(uv > 3) and np.all(uv[:, 0] < w - 4) and np.all(uv[:, 1] < h - 4) and np.all((R @ outline.T).T[:, 2] + t[2] > 0):
            poses.append((R, t))
    return poses


def simulate_intrinsics_set(
    out: Path,
    board: Board,
    intrinsics: CameraIntrinsics,
    n_views: int = 20,
    seed: int = 0,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
    noise_grey: float = 2.0,
    lighting: Lighting | None = None,
    image_ext: str = ".png",
    lens: Any = None,
    printed: Board | None = None,
) -> list[Path]:
    """Render ``n_views`` varied-pose images for intrinsics calibration into ``out``.

    Tilts up to 45 degrees in every direction, the board filling 45-95 % of
    the frame and placed so corners reach the image edges. Writes the images
    (view_000.png ...), board.json, intrinsics_truth.json and poses_truth.json;
    returns the image paths. ``lens`` and ``printed`` (the simulator's realism): the true lens's terms beyond
    ``intrinsics`` and the board as printed (board.json keeps the nominal ``board``).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    lighting = lighting or Lighting()
    rng = np.random.default_rng(seed)
    poses = sample_intrinsics_poses(board, intrinsics, n_views, rng)
    write_board(out / "board.json", board)
    write_intrinsics(out / "intrinsics_truth.json", intrinsics)
    write_json(out / "poses_truth.json", {"R_cam_board": [p[0] for p in poses], "t_cam_board_mm": [p[1] for p in poses],
                                          "noise_grey": noise_grey, "seed": seed})
    paths = []
    progress(0, n_views, "rendering")
    for k, (R, t) in enumerate(poses):
        if cancel is not None:
            cancel.check("intrinsics set simulation")
        data = render_encoded(printed or board, intrinsics, lighting, noise_grey, [(R, t, seed * 100003 + k)],
                              image_ext, lens)[0]
        path = out / f"view_{k:03d}{image_ext}"
        write_bytes_atomic(path, data)
        paths.append(path)
        progress(k + 1, n_views, path.name)
    return paths
