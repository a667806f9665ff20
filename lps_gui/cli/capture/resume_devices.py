"""Which stage and camera a resumed capture opens: only those the operator names.

session.json records the devices a session was captured with, but a session
folder can come from anywhere: opening a port or a network URL
(``socket://host:port``) because a file says so would send G-code (and a
reset byte) to whatever it names. Resume therefore opens only the devices
given on the command line and, when they are missing, says what the
session was captured with so the operator can name them.
"""
from __future__ import annotations

from typing import Any

from lps_gui.errors import InputError


SIMULATED_STAGES = ("sim", "emulator")


def rig_stage_named_by_operator(session: Any, stage: str | None) -> str:
    """The stage a resumed capture on the simulated rig rides: --stage, else sim; a session captured behind
    another stage (marlin:, command:...) needs it named again (InputError naming the recorded one)."""
    recorded = (session.meta.get("stage") or {}).get("spec")
    if stage or recorded in (None, *SIMULATED_STAGES):
        return stage or "sim"
    import shlex

    raise InputError(f"{session.folder}: give --stage to resume with (it was captured with --stage {shlex.quote(recorded)}; "
                     "devices named in a session file are never opened by themselves)")


def devices_named_by_operator(session: Any, stage: str | None, camera: str | None) -> tuple[str, str]:
    """(stage spec, camera spec) from the command line; InputError naming the recorded ones when missing."""
    if stage and camera:
        return stage, camera
    recorded_stage = (session.meta.get("stage") or {}).get("spec")
    recorded_camera = (session.meta.get("camera") or {}).get("spec")
    missing = " and ".join(n for n, v in (("--stage", stage), ("--camera", camera)) if not v)
    hint = ""
    if recorded_stage or recorded_camera:
        hint = f" (it was captured with --stage {recorded_stage or '?'} --camera {recorded_camera or '?'}; devices named " \
               "in a session file are never opened by themselves)"
    raise InputError(f"{session.folder}: give {missing} to resume with{hint}")
