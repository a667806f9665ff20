"""The emulated Basler camera (PYLON_CAMEMU) fed the simulated camera's render of every frame.

pylon's emulator returns the image file named by ``ImageFilename`` byte for
byte (``TestImageSelector=Off``, ``ImageFileMode=On``); it reads the named
file again at every GrabOne, and each render gets its own file in ``feed_dir``
(none is rewritten while pylon may read it). The frame then
comes through the real SDK path: GrabOne, the node map, the pixel format.
"""
from __future__ import annotations

from pathlib import Path

import cv2

from lps_gui.camera.base import Frame
from lps_gui.camera.pylon_camera import PylonCamera
from lps_gui.sim.rig import RigCamera


class FedPylonCamera(PylonCamera):
    def __init__(self, sim: RigCamera, feed_dir: Path, serial: str = "0815-0000") -> None:
        super().__init__(serial, clock=sim.clock)
        self.sim, self.feed_dir = sim, Path(feed_dir)
        self.pose_source = sim.pose_source  # the truth recorder asks the fed camera for the true pose
        self.rig = sim.rig  # the simulator hook (sim/session.SimulatedRigHook) takes the rig from its camera
        self._fed = 0

    def open(self) -> None:
        super().open()
        self.sim.open()
        w, h = self.sim.rig.intrinsics.image_size
        cam = self.device
        cam.Width.SetValue(w)
        cam.Height.SetValue(h)
        cam.PixelFormat.SetValue("Mono8")
        cam.TestImageSelector.SetValue("Off")
        cam.ImageFileMode.SetValue("On")

    def seed_capture(self, key: int) -> None:
        self.sim.seed_capture(key)

    def grab(self) -> Frame:
        rendered = self.sim.grab()
        self._fed += 1
        path = self.feed_dir / f"feed_{self._fed:06d}.png"
        assert cv2.imwrite(str(path), rendered.image)
        self.device.ImageFilename.SetValue(str(path))
        frame = super().grab()
        return Frame(image=frame.image, time=rendered.time, meta={**rendered.meta, **frame.meta})
