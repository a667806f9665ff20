"""Camera sources: the Camera interface, OpenCV devices/files/URLs, folder replay, the simulated camera.

:func:`open_camera` turns the ``--camera`` spec of the CLI and GUI into an
opened :class:`~lps_gui.camera.base.Camera`.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from lps_gui.camera.base import Camera
from lps_gui.camera.sdk_sources import SDK_SPECS, family_of, sdk_camera
from lps_gui.errors import InputError

CAMERA_SPECS = f"sim | N (device index) | {SDK_SPECS} | DIR (replay a folder) | FILE (video or image sequence) | URL"


def open_camera(spec: str, **options: Any) -> Camera:
    """Make and open the camera named by ``spec``.

    ``"sim"`` -> :class:`SimulatedCamera` (needs ``rig`` and ``pose_source``
    keywords, e.g. a simulated stage's ``true_pose``); ``"0"`` -> device 0;
    an existing folder -> :class:`FolderReplayCamera`; a file or a URL ->
    :class:`OpenCVCamera`; ``genicam:``, ``pylon:``, ``gphoto2:``, ``v4l2:``
    -> the SDK family's camera (``cti`` option: the GenTL producer). Other
    ``options`` go to the camera's constructor.
    """
    spec = str(spec).strip()
    camera: Camera
    cti = options.pop("cti", None)
    if family_of(spec) is not None:
        camera = sdk_camera(spec, cti=cti, **options)
    elif spec == "sim":
        if "rig" not in options or "pose_source" not in options:
            raise InputError("camera sim: the simulated camera rides the simulated stage; choose the simulated stage (--stage sim)")
        from lps_gui.camera.sim_camera import SimulatedCamera

        camera = SimulatedCamera(**options)
    elif spec.isdigit():
        from lps_gui.camera.opencv_camera import OpenCVCamera

        camera = OpenCVCamera(int(spec), **options)
    elif Path(spec).is_dir():
        from lps_gui.camera.folder_replay import FolderReplayCamera

        camera = FolderReplayCamera(spec, **options)
    elif "://" in spec or "%" in spec or Path(spec).is_file():
        from lps_gui.camera.opencv_camera import OpenCVCamera

        camera = OpenCVCamera(spec, **options)
    else:
        raise InputError(f"camera {spec!r}: no such device, folder, file or URL; use {CAMERA_SPECS}")
    camera.open()
    return camera
