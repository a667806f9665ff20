"""The simulated XY gantry: a simulated stage with the planar error model and a camera that
renders the board where the carriage really is (SPEC 10).

The planar counterpart of :mod:`lps_gui.sim.rig`, sharing its seeded
devices (:class:`RigStage`, :class:`RigCamera`) so a planar capture killed
and resumed gives the same images as one that ran straight through. Its
truth goes through the same truth.jsonl rules (:mod:`lps_gui.sim.truth`).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.camera_model import project_board
from lps_gui.core.clock import Clock, SimClock
from lps_gui.core.planar_plan import PlanarPlan
from lps_gui.core.planar_rig import PlanarErrorModel, PlanarRig, PlanarTruePose
from lps_gui.core.planar_model import planar_positions_only
from lps_gui.core.planar_simulate import PlanarSimulationSpec, nominal_planar_state
from lps_gui.errors import InputError
from lps_gui.io.board_file import board_from_dict, board_to_dict
from lps_gui.io.intrinsics_file import intrinsics_from_dict, intrinsics_to_dict
from lps_gui.io.session import Session
from lps_gui.sim.rig import RigCamera, RigStage
from lps_gui.sim.truth import TRUTH_FILE, append_truth, prune_truth, read_truth

STAGE_MARGIN_MM = 5.0


def gantry_travel_mm(plan: PlanarPlan, margin_mm: float = STAGE_MARGIN_MM) -> dict[str, tuple[float, float]]:
    """Per-axis soft-limit ranges that hold the plan's targets and overshoots, with a margin."""
    t = plan.targets()
    out = {}
    for a, name in enumerate(("X", "Y")):
        lo = float(t[:, a].min()) - plan.overshoot_mm - margin_mm
        hi = float(t[:, a].max()) + plan.overshoot_mm + margin_mm
        out[name] = (min(lo, -margin_mm), hi)
    return out


def make_simulated_gantry(spec: PlanarSimulationSpec, clock: Clock | None = None, noise_grey: float = 2.0,
                          **options: Any) -> tuple[RigStage, RigCamera]:
    """Build (not connect, not open) the simulated XY stage and the camera bound to its true pose."""
    clock = clock if clock is not None else SimClock()
    stage_keys = {"max_rate_mm_min", "accel_mm_s2", "homing_required", "soft_limits"}
    stage_opts = {k: v for k, v in options.items() if k in stage_keys}
    camera_opts = {k: v for k, v in options.items() if k not in stage_keys}
    travel = gantry_travel_mm(spec.plan)
    stage = RigStage(seed=spec.seed, clock=clock, travel_mm=travel["X"], axis_travel_mm=travel,
                     planar_errors=spec.rig.errors, **stage_opts)
    camera = RigCamera(spec.rig, pose_source=stage.true_planar_pose, noise_grey=noise_grey, seed=spec.seed,
                       clock=clock, **camera_opts)
    return stage, camera


def gantry_truth(spec: PlanarSimulationSpec, camera: RigCamera) -> dict[str, Any]:
    """The static truth of a simulated planar capture (session.json ``truth``), enough to rebuild the rig."""
    return {
        "simulated": True, "axes": ["X", "Y"], "preset": spec.name, "seed": spec.seed, "rig": spec.rig.to_dict(),
        "board": board_to_dict(spec.rig.board), "intrinsics": intrinsics_to_dict(spec.rig.intrinsics),
        "camera": {"noise_grey": camera.noise_grey, "blur_px": camera.lighting.blur_px}, "per_capture": TRUTH_FILE,
        "noise_px": None,
    }


def spec_from_gantry_truth(truth: dict[str, Any], plan: PlanarPlan, source: str = "session.json") -> PlanarSimulationSpec:
    """Rebuild the :class:`PlanarSimulationSpec` recorded by :func:`gantry_truth` (for ``--resume``)."""
    try:
        r = truth["rig"]
        rig = PlanarRig(board_from_dict(truth["board"], source), intrinsics_from_dict(truth["intrinsics"], source),
                        np.asarray(r["R_cam_board"], float), np.asarray(r["C0_board"], float),
                        np.asarray(r["axes_board"], float), PlanarErrorModel.from_dict(r["stage_errors"]))
        return PlanarSimulationSpec(str(truth.get("preset", "sim")), rig, plan, seed=int(truth.get("seed", 0)))
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{source}: the simulated gantry's truth is incomplete ({exc}); start a new session") from exc


class PlanarTruthRecorder:
    """The capture engine's truth hook on the simulated gantry: the true pose of every frame.

    Beside the carriage's true plane position it records the board-plane
    position (what a constant-orientation model sees when the carriage tilts),
    so the comparison needs no re-projection later.
    """

    def __init__(self, rig: PlanarRig, pose_source) -> None:
        self.rig = rig
        self.pose_source = pose_source

    def prune(self, session: Session) -> None:
        prune_truth(session)

    def record(self, session: Session, index: int) -> None:
        pose: PlanarTruePose = self.pose_source()
        R, t = self.rig.camera_poses(pose)
        X = self.rig.board.object_points()
        uv = project_board(R, t, X, self.rig.intrinsics)
        board_plane = planar_positions_only(nominal_planar_state(self.rig, pose.plane_mm), X, uv,
                                            np.ones(uv.shape[:2], bool))
        append_truth(session, index, {
            "plane_mm": [float(v) for v in pose.plane_mm[0]],
            "board_plane_mm": [float(v) for v in board_plane[0]],
            "normal_um": float(pose.normal_um[0]),
            "angles_urad": [float(v) for v in pose.angles_urad[0]],
        })

    def finalize(self, session: Session) -> None:
        per_index = read_truth(session)
        indices = sorted({r.index for r in session.records()} & set(per_index))
        if not indices:
            return
        rows = [per_index[i] for i in indices]
        truth = dict(session.meta.get("truth") or {})
        truth.update({"index": indices, "plane_mm": [r["plane_mm"] for r in rows],
                      "board_plane_mm": [r["board_plane_mm"] for r in rows],
                      "normal_um": [r["normal_um"] for r in rows], "angles_urad": [r["angles_urad"] for r in rows]})
        session.meta["truth"] = truth
        session.save_meta()


def create_simulated_gantry_session(folder, spec: PlanarSimulationSpec, clock: Clock | None = None,
                                    noise_grey: float = 2.0, intrinsics=None, **options: Any):
    """A new session for a planar capture on the simulated gantry: (session, stage, camera)."""
    from lps_gui.io.atomic import check_writable

    check_writable(folder)
    stage, camera = make_simulated_gantry(spec, clock=clock, noise_grey=noise_grey, **options)
    return start_gantry_session(folder, spec, stage, camera, intrinsics), stage, camera


def start_gantry_session(folder, spec: PlanarSimulationSpec, stage: RigStage, camera: RigCamera,
                         intrinsics=None, extra: dict[str, Any] | None = None) -> Session:
    """The session of a capture on an existing simulated gantry (the GUI's, or :func:`create_simulated_gantry_session`'s).

    ``extra``: further session.json entries (the GUI's specification, environment, identification).
    """
    from lps_gui.sim.session import write_simulated_session

    session = write_simulated_session(folder, spec, "capture", intrinsics=intrinsics, camera=camera.properties(),
                                      stage={**stage.describe(), "axes": ["X", "Y"]}, truth=gantry_truth(spec, camera))
    if extra:
        session.meta.update(extra)
        session.save_meta()
    return session


def reopen_simulated_gantry(session: Session, clock: Clock | None = None) -> tuple[RigStage, RigCamera]:
    """Rebuild the simulated gantry a planar session was captured with (for ``--resume``)."""
    truth = session.truth or {}
    if not truth.get("simulated") or truth.get("axes") != ["X", "Y"]:
        raise InputError(f"{session.folder}: not captured on the simulated gantry; resume it with --stage and --camera")
    spec = spec_from_gantry_truth(truth, session.plan(), str(session.folder / "session.json"))
    cam = truth.get("camera") or {}
    return make_simulated_gantry(spec, clock=clock, noise_grey=float(cam.get("noise_grey", 2.0)),
                                 blur_px=float(cam.get("blur_px", 1.2)))


def gantry_engine(session: Session, stage, camera: RigCamera, encode: str = ".png"):
    """A capture engine that also records the true pose of every frame on the simulated gantry."""
    from lps_gui.capture.engine import CaptureEngine

    return CaptureEngine(stage, camera, session, encode=encode,
                         truth_recorder=PlanarTruthRecorder(camera.rig, camera.pose_source))


def check_board_in_view(spec: PlanarSimulationSpec) -> None:
    """InputError when the simulated camera would lose the board at some target (nothing measured there)."""
    t = spec.plan.targets()
    rig = spec.rig
    R, tr = rig.camera_poses(PlanarTruePose(t, np.zeros(len(t)), np.zeros((len(t), 3))))
    uv = project_board(R, tr, rig.board.object_points(), rig.intrinsics)  # shape (K, N, 2)
    w, h = rig.intrinsics.image_size
    out = ((uv[..., 0] < 0) | (uv[..., 0] > w - 1) | (uv[..., 1] < 0) | (uv[..., 1] > h - 1)).any(axis=1)
    if out.any():
        x, y = t[np.flatnonzero(out)[0]]
        raise InputError(f"plan: the board leaves the simulated camera's view at {int(out.sum())} of {len(t)} targets "
                         f"(first ({x:g}, {y:g}) mm); shorten the grid (see `lps plan-rig`)")
