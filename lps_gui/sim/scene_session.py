"""Scene captures on the simulated rig (issue 38): the measured session's plan again, the board replaced by
the light-field scene.

The stage is the one the measurement session was captured on (its truth: mount, errors, camera), the plan
its first pass (same stops, same approach direction and overshoot, one frame a stop), the images the
scene of :func:`lps_gui.core.truth.scene.scene_for_rig` through the same camera model, blur and noise.
The stage draws its repeatability afresh (another seed): a scene capture is a new visit of every stop,
not a replay of the measurement's. session.json ``scene.measurement_session`` names the measurement
(:mod:`lps_gui.io.scene_link`), ``truth.scene`` the scene, so the check can follow known points.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

from lps_gui.core.clock import Clock
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.scene import Scene, scene_for_rig
from lps_gui.core.truth.simulate import SimulationSpec
from lps_gui.errors import InputError
from lps_gui.io.atomic import check_writable
from lps_gui.io.intrinsics_file import intrinsics_to_dict
from lps_gui.io.scene_link import SCENE_KEY, measurement_link
from lps_gui.io.session import Session
from lps_gui.sim.rig import RigCamera, RigStage, make_simulated_rig, rig_truth, spec_from_truth

SCENE_SEED_OFFSET = 1000  # the scene capture's draws differ from the measurement's


def scene_plan(plan: Plan) -> Plan:
    """The measured plan's first pass: every stop once, from the side the measurement's first run took it."""
    return replace(plan, directions=plan.run_directions()[0], runs=1, frames_per_stop=1, segments=None)


def measured_rig_spec(measured: Session) -> SimulationSpec:
    """The simulated rig a measurement session was made on (its truth), with the scene plan and a new seed."""
    truth = dict(measured.truth or {})
    if not truth.get("R_cam_board") and not truth.get("rig"):
        raise InputError(f"{measured.folder}: not measured on the simulated rig; capture its scene on the real "
                         "devices (--stage ... --camera ...)")
    if "intrinsics" not in truth:  # a point-level gantry session keeps the true intrinsics as its own
        truth["intrinsics"] = intrinsics_to_dict(measured.intrinsics())
    plan = scene_plan(measured.plan())
    spec = spec_from_truth(truth, plan, str(measured.folder / "session.json"))
    return replace(spec, seed=spec.seed + SCENE_SEED_OFFSET, layout=None)


def create_scene_session(folder: Path | str, measured: Session, clock: Clock | None = None,
                         noise_grey: float = 2.0, **options: Any) -> tuple[Session, RigStage, RigCamera]:
    """A new scene session in ``folder`` on the measured session's simulated rig (stage not yet connected)."""
    check_writable(folder)
    link = measurement_link(measured)  # refuses a measurement without results.json before anything is made
    spec = measured_rig_spec(measured)
    scene = scene_for_rig(spec.rig, spec.plan.targets())
    cam = (measured.truth or {}).get("camera") or {}
    options.setdefault("blur_px", float(cam.get("blur_px", 1.2)))
    stage, camera = make_simulated_rig(spec, clock=clock, noise_grey=noise_grey, scene=scene, **options)
    described = {**stage.describe(), "axes": ["X", "Y"]} if spec.plan.planar else stage.describe()
    session = Session.create(
        folder, board=measured.targets() or measured.board(), plan=spec.plan, intrinsics=measured.intrinsics(), camera=camera.properties(),
        stage=described, truth={**rig_truth(spec, camera), "scene": scene.to_dict()},
        extra={SCENE_KEY: {"measurement_session": link},
               "simulation": {"preset": spec.name, "seed": spec.seed, "level": "scene"}})
    return session, stage, camera


def session_scene(session: Session) -> Scene | None:
    """The simulated scene a scene session was rendered from (its truth), None for a real one."""
    d = (session.truth or {}).get("scene")
    return Scene.from_dict(d) if isinstance(d, dict) else None
