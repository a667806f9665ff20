"""The simulated rig: a simulated stage (one axis or an XY gantry) and a simulated camera that renders
where the stage really is.

One :class:`~lps_gui.core.truth.simulate.SimulationSpec` describes it; the stage
carries the spec's error model (a :class:`StageErrorModel`, or a
:class:`PlanarErrorModel` on two axes), the camera renders the board through
the stage's true pose, both run on one clock (a :class:`SimClock` unless
told otherwise). The CLI, the GUI and the demo use :func:`make_simulated_rig`;
the stage error models and the rig geometry they bind are pure models in
``core/truth/stage_errors.py`` and ``core/truth/rig.py``.

Both devices can be seeded (``seed_capture(key)``, through the capture
engine's one simulator hook, :class:`lps_gui.sim.session.SimulatedRigHook`):
the stage's repeatability draw for a stop and the camera's image noise for a
frame come from generators seeded by (seed, capture index), so a capture
killed and resumed yields the same images, byte for byte, as one that ran
straight through.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from lps_gui.camera.sim_camera import SimulatedCamera
from lps_gui.core.clock import Clock, SimClock
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.realism import Realism
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulate import SimulationSpec, layout_truth, preset
from lps_gui.core.truth.stage_errors import PlanarErrorModel, PlanarTruePose, StageErrorModel
from lps_gui.errors import InputError
from lps_gui.hardware.sim_stage import SimulatedStage
from lps_gui.io.board_file import board_from_dict, board_to_dict
from lps_gui.io.intrinsics_file import intrinsics_from_dict, intrinsics_to_dict
from lps_gui.sim.truth import TRUTH_FILE

_STAGE_STREAM, _CAMERA_STREAM = 0, 1  # independent noise streams per capture


class RigStage(SimulatedStage):
    """A :class:`SimulatedStage` whose repeatability draw per stop is seeded by the capture index."""

    _axis_keys: tuple[int, int] | None = None  # an XY gantry's per-axis keys (seed_axes); None: one draw per move

    def seed_capture(self, key: int) -> None:
        """Seed the draw of the next completed move (the move onto stop ``key``)."""
        with self._lock:
            self._rng = np.random.default_rng([self.seed, int(key), _STAGE_STREAM])

    def seed_axes(self, key_x: int, key_y: int) -> None:
        """Key each XY axis' repeatability draw on the frame it arrived at (Plan.arrival_indices)."""
        with self._lock:
            self._axis_keys = (int(key_x), int(key_y))

    def _axis_rng(self, axis: int) -> np.random.Generator:
        """An XY axis draws one value per arrival, however many moves reach it (a resume adds overshoots)."""
        keys = self._axis_keys
        if keys is None:
            return self._rng
        return np.random.default_rng([self.seed, keys[axis], _STAGE_STREAM, 1 + axis])


class RigCamera(SimulatedCamera):
    """A :class:`SimulatedCamera` whose image noise is seeded by the capture index.

    ``faults``: an :class:`~lps_gui.sim.faults.InjectedFaults`, told the index of every grab.
    """

    def __init__(self, *args: Any, faults: Any = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.faults = faults

    def seed_capture(self, key: int) -> None:
        """Seed the noise of the next grab (capture ``key``)."""
        self._rng = np.random.default_rng([self.seed, int(key), _CAMERA_STREAM])
        if self.faults is not None:
            self.faults.at(key)

    def rendered_pose(self) -> Any:
        """The pose the last frame was rendered at (a ringing stage has moved on by the end of the exposure)."""
        return self.pose_source() if self.last_pose is None else self.last_pose


STAGE_MARGIN_MM = 5.0


def stage_travel_mm(plan: Plan, margin_mm: float = STAGE_MARGIN_MM) -> tuple[float, float]:
    """Soft-limit range that holds a one-axis plan's targets and overshoots, with a margin."""
    t = plan.targets()
    lo = float(t[0]) - plan.overshoot_mm - margin_mm
    hi = float(t[-1]) + plan.overshoot_mm + margin_mm
    return (min(lo, -margin_mm), max(hi, 500.0))


def gantry_travel_mm(plan: Plan, margin_mm: float = STAGE_MARGIN_MM) -> dict[str, tuple[float, float]]:
    """Per-axis soft-limit ranges that hold a two-axis plan's targets and overshoots, with a margin."""
    t = plan.targets()
    out = {}
    for a, name in enumerate(("X", "Y")):
        lo = float(t[:, a].min()) - plan.overshoot_mm - margin_mm
        hi = float(t[:, a].max()) + plan.overshoot_mm + margin_mm
        out[name] = (min(lo, -margin_mm), hi)
    return out


def make_simulated_rig(
    spec: SimulationSpec,
    clock: Clock | None = None,
    noise_grey: float = 2.0,
    **options: Any,
) -> tuple[RigStage, RigCamera]:
    """Build (not connect, not open) the simulated stage and the camera bound to its true pose.

    Parameters
    ----------
    spec : rig (board, intrinsics, mount, stage errors), plan and ``seed``; a two-axis plan makes an XY gantry
        whose X and Y both carry the camera.
    clock : shared by stage and camera; a fresh :class:`SimClock` when None.
    noise_grey : image noise sigma in grey levels.
    options : ``max_rate_mm_min``, ``accel_mm_s2``, ``vibration`` go to the stage, the rest
        (``blur_px``, ``exposure_s``...) to the camera's renderer.
    """
    clock = clock if clock is not None else SimClock()
    stage_keys = {"max_rate_mm_min", "accel_mm_s2", "homing_required", "soft_limits", "vibration"}  # "faults": the camera's
    stage_opts = {k: v for k, v in options.items() if k in stage_keys}
    camera_opts = {k: v for k, v in options.items() if k not in stage_keys}
    if spec.plan.planar:
        travel = gantry_travel_mm(spec.plan)
        stage = RigStage(seed=spec.seed, clock=clock, travel_mm=travel["X"], axis_travel_mm=travel,
                         planar_errors=spec.rig.errors, **stage_opts)
        pose_source = stage.true_planar_pose
    else:
        stage = RigStage(errors=spec.rig.errors, seed=spec.seed, clock=clock, travel_mm=stage_travel_mm(spec.plan),
                         **stage_opts)
        pose_source = stage.true_pose
    camera = RigCamera(spec.rig, pose_source=pose_source, noise_grey=noise_grey, seed=spec.seed, clock=clock,
                       layout=spec.layout, **{**spec.camera_realism(), **camera_opts})
    return stage, camera


def spec_for_plan(preset_name: str, plan: Plan | None = None, seed: int = 0) -> SimulationSpec:
    """A preset's rig re-aimed so the board is centred over ``plan``'s travel.

    The preset's camera distance, tilt, axis misalignment and stage errors
    are kept; only the mount moves so the middle of the travel sees the
    board centre.
    """
    spec = preset(preset_name, seed=seed)
    if plan is None:
        return spec
    rig = spec.rig
    t_old, t_new = spec.plan.targets(), plan.targets()
    mid_old = 0.5 * (t_old[0] + t_old[-1])
    mid_new = 0.5 * (t_new[0] + t_new[-1])
    C0 = rig.C0_board + (mid_old - mid_new) * rig.u_board
    return replace(spec, rig=replace(rig, C0_board=C0), plan=plan)


def rig_truth(spec: SimulationSpec, camera: SimulatedCamera) -> dict[str, Any]:
    """The static truth of a simulated capture for session.json (per-capture truth comes later).

    Holds everything :func:`spec_from_truth` needs to rebuild the same rig on
    ``lps capture --resume``, with the field names of :func:`core.simulate.true_views`
    (a gantry's: ``axes`` and the ``rig`` of SPEC 10).
    """
    if spec.plan.planar:
        return {
            "simulated": True, "axes": ["X", "Y"], "preset": spec.name, "seed": spec.seed, "rig": spec.rig.to_dict(),
            "board": board_to_dict(spec.rig.board), "intrinsics": intrinsics_to_dict(spec.rig.intrinsics),
            "camera": {"noise_grey": camera.noise_grey, "blur_px": camera.lighting.blur_px}, "per_capture": TRUTH_FILE,
            "noise_px": None, **({} if spec.layout is None else {"targets": layout_truth(spec.layout)}),
            **spec.realism_truth(), **_print_seed(spec),
        }
    return {
        "simulated": True,
        "preset": spec.name,
        "seed": spec.seed,
        "R_cam_board": spec.rig.R_cam_board.tolist(),
        "C0_board": spec.rig.C0_board.tolist(),
        "u_board": spec.rig.u_board.tolist(),
        "stage_errors": spec.rig.errors.to_dict(),
        "board": board_to_dict(spec.rig.board),
        "intrinsics": intrinsics_to_dict(spec.rig.intrinsics),
        "camera": {"noise_grey": camera.noise_grey, "blur_px": camera.lighting.blur_px},
        "per_capture": TRUTH_FILE,
        **({} if spec.layout is None else {"targets": layout_truth(spec.layout)}),
        **spec.realism_truth(), **_print_seed(spec),
    }


def _print_seed(spec: SimulationSpec) -> dict[str, Any]:
    """truth ``print_seed``: a re-capture's prints are its first capture's (``--resume`` redraws them alike)."""
    return {} if spec.print_seed is None else {"print_seed": spec.print_seed}


def spec_from_truth(truth: dict[str, Any], plan: Plan, source: str = "session.json") -> SimulationSpec:
    """Rebuild the :class:`SimulationSpec` recorded by :func:`rig_truth` (a rig or a gantry, as ``plan``)."""
    what = "gantry" if plan.planar else "rig"
    try:
        board, intrinsics = board_from_dict(truth["board"], source), intrinsics_from_dict(truth["intrinsics"], source)
        if plan.planar:
            r = truth["rig"]
            rig = Rig(board, intrinsics, np.asarray(r["R_cam_board"], float), np.asarray(r["C0_board"], float),
                      np.asarray(r["axes_board"], float), PlanarErrorModel.from_dict(r["stage_errors"]))
        else:
            rig = Rig(
                board=board,
                intrinsics=intrinsics,
                R_cam_board=np.asarray(truth["R_cam_board"], dtype=float),
                C0_board=np.asarray(truth["C0_board"], dtype=float),
                axes_board=np.asarray(truth["u_board"], dtype=float),
                errors=StageErrorModel.from_dict(truth["stage_errors"]),
            )
        return SimulationSpec(str(truth.get("preset", "sim")), rig, plan, seed=int(truth.get("seed", 0)),
                              realism=Realism.from_dict(_switches(truth.get("realism"))),
                              print_seed=None if truth.get("print_seed") is None else int(truth["print_seed"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{source}: the simulated {what}'s truth is incomplete ({exc}); start a new session") from exc


def _switches(realism: dict[str, Any] | None) -> dict[str, Any] | None:
    """truth.realism without what it derives (the lens for this camera, the prints): the switches to rebuild it."""
    if not realism:
        return None
    return {k: v for k, v in realism.items() if k not in ("lens", "printed")}


def check_board_in_view(spec: SimulationSpec) -> None:
    """InputError when the simulated gantry's camera would lose the board at some target (nothing measured there)."""
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
