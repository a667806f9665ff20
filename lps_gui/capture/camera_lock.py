"""Camera controls locked for a whole capture, recorded in session.json, checked on every frame.

The same holds for what a frame is made of: its size must be the one the
session's intrinsics were calibrated at (a 1024x1040 frame measured with
1920x1080 intrinsics fails every detection later), and a raw Bayer camera's
sub-lattice gains, fixed at the first frame, are recorded and reused by a
resumed capture instead of being estimated again from another frame.

At the start of a run the automatic modes go off and the values in force are
recorded (``session.json`` ``camera.controls``); a resumed capture puts the
recorded values back first. A frame whose reported exposure or gain differs
from the locked value is refused with one line (the engine pauses; nothing is
listed for it): corners seen at another exposure are not the same measurement.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.camera import controls
from lps_gui.camera.base import Camera, Frame
from lps_gui.camera.control_surface import CHECKED
from lps_gui.errors import HardwareError, InputError
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
    gains = (session.meta.get("camera") or {}).get("bayer_gains")
    if gains is not None and callable(getattr(camera, "set_bayer_gains", None)):
        camera.set_bayer_gains(_checked_gains(gains, session))
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


def _checked_gains(gains: Any, session: Session) -> np.ndarray:
    """The recorded Bayer gains as a (2, 2) array of positive numbers, or one line naming session.json."""
    try:
        out = np.asarray(gains, dtype=np.float64).reshape(2, 2)
    except (TypeError, ValueError):
        out = np.full((2, 2), np.nan)
    if not (np.isfinite(out).all() and (out > 0).all()):
        raise InputError(f"{session.folder / 'session.json'}: camera.bayer_gains must be 2x2 positive numbers; "
                         "restore it from a backup or delete the entry to estimate them again")
    return out


def record_bayer_gains(camera: Camera, session: Session) -> None:
    """After a frame: record the gains a raw Bayer frame fixed, once, before the frame is listed."""
    gains = getattr(camera, "bayer_gains", None)
    meta = session.meta.setdefault("camera", {})
    if gains is not None and meta.get("bayer_gains") is None:
        meta["bayer_gains"] = gains
        session.save_meta()


def expected_frame_size(session: Session) -> tuple[int, int] | None:
    """(width, height) of the session's intrinsics; None when it has none yet."""
    if not session.has_intrinsics():
        return None
    return tuple(int(v) for v in session.intrinsics().image_size)  # type: ignore[return-value]


def check_frame_size(expected: tuple[int, int] | None, frame: Frame, index: int) -> None:
    """HardwareError when the frame's size is not the intrinsics' (every detection would fail later)."""
    if expected is not None and tuple(frame.size) != tuple(expected):
        (w, h), (ew, eh) = frame.size, expected
        raise HardwareError(f"camera: frame {index} refused, it is {w}x{h} but the intrinsics are for {ew}x{eh}; "
                            "set the camera's width, height and binning as when it was calibrated (or calibrate at "
                            "this size), then resume")
