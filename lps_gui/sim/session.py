"""The one writer of simulated sessions, and capture sessions on the simulated rig.

Every simulated session (corner level, rendered images, the capture engine
on the simulated rig, the demo, the GUI) gets its session.json from
:func:`write_simulated_session`: the rig's board and plan, the truth, and a
``simulation`` record (preset, seed, level). A capture on the simulated rig
records the rig itself (:func:`lps_gui.sim.rig.rig_truth`), so
``lps capture --resume`` rebuilds the same stage error model, mount and
camera and goes on as if nothing happened; per-capture truth goes to
a sidecar and, once complete, into session.json (:mod:`lps_gui.sim.truth`).
A two-axis plan (SPEC 10) makes the same on the simulated XY gantry.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from lps_gui.capture.engine import CaptureEngine
from lps_gui.core.clock import Clock
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.planning.plan import Plan, PlannedStop
from lps_gui.core.truth.simulate import SimulationSpec
from lps_gui.core.truth.stage_errors import Vibration
from lps_gui.errors import InputError
from lps_gui.hardware.stage import Stage
from lps_gui.io.atomic import check_writable
from lps_gui.io.session import Session
from lps_gui.sim.rig import RigCamera, RigStage, make_simulated_rig, rig_truth, spec_from_truth
from lps_gui.sim.truth import TruthRecorder


def write_simulated_session(
    folder: Path | str,
    spec: SimulationSpec,
    level: str,
    *,
    intrinsics: CameraIntrinsics | str | None,
    camera: dict[str, Any],
    stage: dict[str, Any],
    truth: dict[str, Any],
    **simulation: Any,
) -> Session:
    """Create the session folder of a simulated experiment (session.json only; captures follow).

    ``level`` says how it was made (``"points"``, ``"images"``, ``"capture"``);
    ``simulation`` adds fields to session.json's ``simulation`` record. A spec
    with a layout of targets (SPEC 13) names its ``targets`` instead of a board; a stitched one (one board moved
    between segments) its board, and the stage's repeatability R = 4 sigma (ISO 230-2) in ``stage_spec``: the
    ties between segments rest on it (:mod:`lps_gui.pipeline.stitched_session`).
    """
    extra: dict[str, Any] = {}
    if spec.stitched:
        extra["stage_spec"] = {"repeatability_um": 4.0 * spec.rig.errors.repeatability_um}
    return Session.create(
        folder,
        board=spec.rig.board if spec.one_board else list(spec.layout.targets),
        plan=spec.plan,
        intrinsics=intrinsics if intrinsics is not None else spec.rig.intrinsics,
        camera=camera,
        stage=stage,
        truth=truth,
        extra={**extra, "simulation": {"preset": spec.name, "seed": spec.seed, "level": level, **simulation}},
    )


def start_rig_session(
    folder: Path | str,
    spec: SimulationSpec,
    stage: RigStage,
    camera: RigCamera,
    intrinsics: CameraIntrinsics | str | None = None,
    extra: dict[str, Any] | None = None,
) -> Session:
    """The session of a capture on an existing simulated rig or gantry (the GUI's, or :func:`create_simulated_session`'s).

    ``extra``: further session.json entries (the GUI's specification, environment, identification).
    """
    described = {**stage.describe(), "axes": ["X", "Y"]} if spec.plan.planar else stage.describe()
    session = write_simulated_session(folder, spec, "capture", intrinsics=intrinsics, camera=camera.properties(),
                                      stage=described, truth=rig_truth(spec, camera))
    if extra:
        session.meta.update(extra)
        session.save_meta()
    return session


def create_simulated_session(
    folder: Path | str,
    spec: SimulationSpec,
    clock: Clock | None = None,
    noise_grey: float = 2.0,
    intrinsics: CameraIntrinsics | str | None = None,
    **options: Any,
) -> tuple[Session, RigStage, RigCamera]:
    """Create a session for ``spec`` and its rig (stage not yet connected); a two-axis plan makes a gantry.

    ``intrinsics`` default to the rig's true intrinsics (a simulation knows
    them); pass calibrated ones to test the effect of calibration error.
    """
    check_writable(folder)
    stage, camera = make_simulated_rig(spec, clock=clock, noise_grey=noise_grey, **options)
    return start_rig_session(folder, spec, stage, camera, intrinsics), stage, camera


def reopen_simulated_rig(session: Session, clock: Clock | None = None) -> tuple[RigStage, RigCamera]:
    """Rebuild the simulated rig (or gantry) a session was captured with (for ``--resume``)."""
    truth = session.truth or {}
    if session.planar and (not truth.get("simulated") or truth.get("axes") != ["X", "Y"]):
        raise InputError(f"{session.folder}: not captured on the simulated gantry; resume it with --stage and --camera")
    if not truth.get("simulated"):
        raise InputError(f"{session.folder}: not captured on the simulated rig; resume it with --stage and --camera")
    scene = truth.get("scene")  # a scene session (issue 38): the scene instead of any board or targets
    spec = spec_from_truth(truth, session.plan(), str(session.folder / "session.json")) if scene else \
        spec_of_session(session)
    cam = truth.get("camera") or {}
    ring = (session.meta.get("stage") or {}).get("vibration")  # the stage rang after each move (settling tests)
    options: dict[str, Any] = {"vibration": Vibration.from_dict(ring)} if isinstance(ring, dict) else {}
    exposure = (session.meta.get("camera") or {}).get("exposure_s")  # its frames took time (frame times)
    if exposure:
        options["exposure_s"] = float(exposure)
    if scene:
        from lps_gui.core.truth.scene import Scene

        options["scene"] = Scene.from_dict(scene)
    return make_simulated_rig(spec, clock=clock, noise_grey=float(cam.get("noise_grey", 2.0)),
                              blur_px=float(cam.get("blur_px", 1.2)), **options)


def spec_of_session(session: Session) -> SimulationSpec:
    """The :class:`SimulationSpec` a capture on the simulated rig recorded (:func:`spec_from_truth`), with a
    session's targets (SPEC 13) at their true poses."""
    truth = session.truth or {}
    spec = spec_from_truth(truth, session.plan(), str(session.folder / "session.json"))
    targets = session.targets()
    if targets is None:
        return spec
    from dataclasses import replace

    return replace(spec, layout=layout_from_truth(targets, truth, str(session.folder / "session.json")))


def layout_from_truth(targets: list, truth: dict[str, Any], source: str):
    """The targets at the poses session.json ``truth.targets`` records (a capture on the simulated rig)."""
    import numpy as np

    from lps_gui.core.geometry.rotation import exp_so3
    from lps_gui.core.geometry.target_rig import TargetLayout

    poses = {t.get("id"): t for t in truth.get("targets") or []}
    missing = [t.id for t in targets if t.id not in poses]
    if missing:
        raise InputError(f"{source}: the simulated row's truth has no pose of target {missing[0]}; start a new session")
    Q = np.stack([exp_so3(np.asarray(poses[t.id]["rvec_rad"], float)) for t in targets])
    p = np.array([poses[t.id]["p_mm"] for t in targets], float)
    return TargetLayout(tuple(targets), Q, p)


class SimulatedRigHook:
    """The capture engine's one hook on a simulated rig (``capture.engine.SimulatorHook``).

    It records the pose the camera renders beside every frame (:class:`TruthRecorder`)
    and seeds the draws: the stage's repeatability per stop (on a gantry per
    axis, keyed on the frame each axis arrived at, ``Plan.arrival_indices``)
    and the camera's image noise per frame, from (seed, capture index), so a
    capture killed and resumed yields the same images as one that ran
    straight through. ``stage``: the rig's stage, also when the engine drives
    the driver in front of it (an emulator serving it); None: a stage whose draws are not seeded.
    """

    def __init__(self, plan: Plan, stage: RigStage | None, camera: RigCamera) -> None:
        self.plan = plan
        self.stage = stage
        self.camera = camera
        rendered = getattr(camera, "rendered_pose", camera.pose_source)  # a camera feeding the rig's frames may not say
        self.truth = TruthRecorder(rendered, camera.rig if camera.rig.planar else None)
        self._arrivals: dict[int, tuple[int, ...]] | None = None

    def prune(self, session: Session) -> None:
        self.truth.prune(session)

    def record(self, session: Session, index: int) -> None:
        self.truth.record(session, index)

    def finalize(self, session: Session) -> None:
        self.truth.finalize(session)

    def seed_stop(self, stop: PlannedStop) -> None:
        if self.stage is None:
            return
        self.stage.seed_capture(stop.index - stop.frame)
        if self.plan.planar:
            if self._arrivals is None:
                self._arrivals = self.plan.arrival_indices()
            self.stage.seed_axes(*self._arrivals[stop.index])

    def seed_frame(self, index: int) -> None:
        self.camera.seed_capture(index)


def simulated_engine(session: Session, stage: Stage, camera: RigCamera, encode: str = ".png") -> CaptureEngine:
    """A :class:`CaptureEngine` that also records the true pose of every frame (the pose the camera renders)
    and seeds the rig's draws (:class:`SimulatedRigHook`).

    ``stage`` is the rig's stage or a driver in front of it (an emulator serving it).
    """
    rig_stage = stage if isinstance(stage, RigStage) else getattr(stage, "simulated", None)  # direct, behind an
    # emulator, or None: another stage the rig follows (sim/follow.py)
    hook = SimulatedRigHook(session.plan(), rig_stage if isinstance(rig_stage, RigStage) else None, camera)
    return CaptureEngine(stage, camera, session, encode=encode, simulator=hook)
