"""Camera controls locked for a whole capture, recorded in session.json, checked on every frame.

At the start of a run the automatic modes go off and the values in force are
recorded (``session.json`` ``camera.controls``); a resumed capture puts the
recorded values back first. A frame whose reported exposure or gain differs
from the locked value is refused with one line (the engine pauses; nothing is
listed for it): corners seen at another exposure are not the same measurement.
"""
from __future__ import annotations

from typing import Any

from lps_gui.camera import controls
from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.control_surface import CHECKED
from lps_gui.errors import HardwareError
from lps_gui.io.session import Session

RELATIVE_TOLERANCE = 1e-3  # devices round a set value to their register step


def lock_camera(camera: Camera, session: Session) -> dict[str, Any]:
    """Lock the controls (to the recorded values when the session has them) and record them; the locked values.

    An SDK camera streaming for a preview is switched to fresh frames: each frame of the capture is its
    own acquisition, started after the stage stood still.
    """
    fresh = getattr(camera, "set_streaming", None)
    if callable(fresh):
        fresh(False)
    recorded = (session.meta.get("camera") or {}).get("controls_locked")
    if recorded:
        refused = controls.apply(camera, recorded)
        if refused:
            raise HardwareError(f"camera: will not take back the recorded {', '.join(refused)} of this session; "
                                "set them on the device as in session.json, then resume")
        return dict(recorded)
    locked = controls.lock(camera)
    if locked:  # cameras without controls (simulated, files) leave session.json as it was
        session.meta.setdefault("camera", {})["controls_locked"] = locked
        session.save_meta()
    return locked


def check_frame(locked: dict[str, Any], frame: Frame, index: int) -> None:
    """HardwareError naming the control when the frame's exposure or gain is not the locked value."""
    seen = frame.meta.get("controls") or {}
    for name in CHECKED:
        if name not in locked or name not in seen:
            continue
        want, got = locked[name], seen[name]
        same = (want == got) if isinstance(want, str) or isinstance(got, str) else \
            abs(float(got) - float(want)) <= RELATIVE_TOLERANCE * max(abs(float(want)), 1e-9)
        if not same:
            raise HardwareError(f"camera: frame {index} refused, {name} is {got} but was locked at {want}; "
                                "switch off the automatic mode or the other program changing it, then resume")
