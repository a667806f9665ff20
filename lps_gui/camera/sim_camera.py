"""A simulated camera: renders the board where the simulated stage really put the camera.

The truth comes from ``pose_source`` (e.g. ``SimulatedStage.true_pose``), a
callable returning the carriage's :class:`TruePose` (K=1) at the moment of the
grab; the rig turns it into the camera pose and :class:`BoardRenderer` makes
the image. Time comes from a :class:`Clock`, so captures under a SimClock
never sleep for real.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.render import BoardRenderer, Lighting
from lps_gui.core.clock import Clock, RealClock
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.stage_errors import TruePose
from lps_gui.errors import HardwareError

LIGHTING_KEYS = tuple(Lighting.__dataclass_fields__)


class SimulatedCamera(Camera):
    """A :class:`Camera` whose frames are rendered images of the rig's board.

    Parameters
    ----------
    rig : board, intrinsics and how the camera rides the stage.
    pose_source : returns the carriage's true pose now (TruePose with K=1).
    noise_grey : Gaussian noise sigma in grey levels.
    seed : seeds the image noise; frames are reproducible in grab order.
    clock : timestamps frames and spends ``exposure_s`` per grab.
    layout : a row or constellation of targets (SPEC 13) rendered instead of the rig's board
        (the rig's board frame is then the first target's, the world frame).
    scene : a light-field scene (``core/truth/scene.Scene``) rendered instead of any board (issue 38).
    render_options : ``margin_squares``, ``exposure_s`` and any
        :class:`Lighting` field (``blur_px``, ``vignetting``, ``texture``...).
    lens, printed : the simulator's realism (:mod:`lps_gui.core.truth.realism`): the true lens's terms beyond
        the rig's intrinsics, and the board (or layout) as printed; None: the rig's own.
    """

    def __init__(
        self,
        rig: Rig,
        pose_source: Callable[[], TruePose],
        noise_grey: float = 2.0,
        seed: int = 0,
        clock: Clock | None = None,
        layout: Any = None,
        lens: Any = None,
        printed: Any = None,
        scene: Any = None,
        **render_options: Any,
    ) -> None:
        self.rig = rig
        self.layout = layout
        self.lens = lens
        self.printed = printed
        self.scene = scene
        self.pose_source = pose_source
        self.noise_grey = float(noise_grey)
        self.seed = int(seed)
        self.clock = clock or RealClock()
        opts = dict(render_options)
        self.exposure_s = float(opts.pop("exposure_s", 0.0))
        self.margin_squares = float(opts.pop("margin_squares", 1.0 if layout is None else 0.5))  # rows: papers abut
        unknown = set(opts) - set(LIGHTING_KEYS)
        if unknown:
            raise TypeError(f"SimulatedCamera: unknown render options {sorted(unknown)}")
        self.lighting = Lighting(**opts)
        self._renderer: Any = None
        self._rng = np.random.default_rng(self.seed)
        self._frame_no = 0
        self.last_pose: Any = None  # the pose of the last frame rendered (its truth)
        self._open = False
        self.faults: Any = None  # a simulator's injected faults (lps_gui.sim.faults): camera_pose(R, t), image(image)

    def open(self) -> None:
        if self._renderer is None and self.scene is not None:  # the light-field scene, no board in view
            from lps_gui.camera.render_scene import SceneRenderer

            self._renderer = SceneRenderer(self.scene, self.rig.intrinsics, self.lighting, self.noise_grey)
        if self._renderer is None and self.layout is not None:  # every target of the row in one scene
            from lps_gui.camera.render_targets import TargetsRenderer

            self._renderer = TargetsRenderer(self.printed or self.layout, self.rig.intrinsics, self.lighting,
                                             self.noise_grey, self.margin_squares, lens=self.lens)
        if self._renderer is None:  # the per-pixel rays take a moment: build once
            self._renderer = BoardRenderer(
                self.printed or self.rig.board, self.rig.intrinsics, self.margin_squares, self.lighting,
                self.noise_grey, lens=self.lens,
            )
        self._open = True

    def grab(self) -> Frame:
        """Render the board (or the targets) at the stage's true pose now; 8-bit grey (H, W)."""
        if not self._open or self._renderer is None:
            raise HardwareError("simulated camera: grab before open(); open the camera first")
        pose = self.pose_source()
        self.last_pose = pose  # the truth of this frame: its exposure starts here (the stage may ring)
        R, t = self.rig.camera_poses(pose)
        if self.faults is not None:
            R, t = self.faults.camera_pose(R, t)
        self.clock.sleep(self.exposure_s)
        image = self._renderer.render(R[0], t[0], self._rng)
        if self.faults is not None:
            image = self.faults.image(image)
        self._frame_no += 1
        meta = {
            "frame": self._frame_no,
            "true_axis_mm": float(np.asarray(getattr(pose, "axis_mm", getattr(pose, "plane_mm", np.nan))).ravel()[0]),
        }
        return Frame(image=image, time=self.clock.now(), meta=meta)

    def properties(self) -> dict[str, Any]:
        w, h = self.rig.intrinsics.image_size
        return {
            "driver": "SimulatedCamera",
            "width": w,
            "height": h,
            "noise_grey": self.noise_grey,
            "seed": self.seed,
            "blur_px": self.lighting.blur_px,
            **({"exposure_s": self.exposure_s} if self.exposure_s else {}),  # a frame takes this (simulated) time
        }
