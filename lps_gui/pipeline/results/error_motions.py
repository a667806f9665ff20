"""results.json ``error_motions`` and the SPEC 14 columns of positions.csv, from every stop's full pose.

The six error motions of an axis (ISO 230-1: EXX, EYX, EZX, EAX, EBX, ECX) come
from one place, :func:`lps_gui.core.metrology.error_motions.error_motions`, whatever gave
the poses: a constellation's joint pose solve (targets at two depths resolve
all three angles) or a single board's per-view 6-DOF fit (the rotation about the
viewing direction resolved, the two tilts not: SPEC 11). Each motion is marked
resolved or not by :mod:`lps_gui.core.metrology.resolution`'s profile rule; positions.csv
carries the angles only where resolved. A tool point in session.json turns the
angles into the positioning error there (Abbe).

session.json ``tool_point``: ``{"offset_mm": [x, y, z], "frame": "stage"}``, the
tool's offset from the camera centre along the stage axes (X along the motion, Z
towards the targets, Y = Z x X) or, with ``"frame": "camera"``, along the
camera's x (right), y (down), z (viewing direction).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.metrology.error_motions import (
    ANGULAR,
    PLANAR_ANGLE_NAMES,
    PLANAR_MOTIONS,
    ErrorMotions,
    error_motions,
    iso_names,
    planar_error_motions,
)
from lps_gui.core.metrology.resolution import with_profile_resolution
from lps_gui.core.models.lps_model import motion_frame
from lps_gui.core.models.pose_model import PoseSolution, pose_solution_from_views
from lps_gui.errors import InputError
from lps_gui.io.results.document import json_float, json_floats
from lps_gui.io.results.keys import SIGMA_TOTAL_UM
from lps_gui.io.results.sections import ErrorMotions as ErrorMotionsSection

ANGLE_COLUMNS = {"roll": "eax", "pitch": "ebx", "yaw": "ecx"}  # SPEC 14's column stems (for every axis)
UNITS = {"positioning": "um", "straightness_y": "um", "straightness_z": "um", "roll": "urad", "pitch": "urad",
         "yaw": "urad"}
BASIS_BOARD = "per-view 6-DOF poses against one board (the tilts need targets at two depths)"
BASIS_TARGETS = "every stop's full pose, jointly with the targets"
WARM_START_MAX_PX = 2.0  # the row model's residual up to which its solution starts the pose solve


@dataclass(frozen=True)
class ToolPoint:
    offset_mm: tuple[float, float, float]
    frame: str  # "stage" or "camera"

    def kwargs(self) -> dict[str, np.ndarray]:
        key = "tool_stage_mm" if self.frame == "stage" else "tool_cam_mm"
        return {key: np.asarray(self.offset_mm, float)}


def tool_point(meta: dict[str, Any], where: str) -> ToolPoint | None:
    """session.json ``tool_point``, checked (None when the session names none)."""
    tp = meta.get("tool_point")
    if tp is None:
        return None
    offset = tp.get("offset_mm") if isinstance(tp, dict) else None
    frame = tp.get("frame", "stage") if isinstance(tp, dict) else None
    ok = (isinstance(offset, list) and len(offset) == 3
          and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in offset))
    if not ok or frame not in ("stage", "camera"):
        raise InputError(f"{where}: tool_point must be {{\"offset_mm\": [x, y, z], \"frame\": \"stage\"|\"camera\"}} "
                         f"(mm from the camera centre), not {tp!r}")
    return ToolPoint((float(offset[0]), float(offset[1]), float(offset[2])), frame)


def board_pose_solution(est: Any) -> PoseSolution | None:
    """A single-board estimate's per-view 6-DOF poses as a pose solution (None without the 6-DOF fit)."""
    six = getattr(est, "six_dof", None)
    if six is None or six.poses is None:
        return None
    return pose_solution_from_views(six.poses.R, six.poses.t, six.poses.cov_unit, est.used, six.sigma2_px)


@dataclass
class ErrorMotionResults:
    section: dict[str, Any]  # results.json ``error_motions``
    columns: dict[str, list[Any]]  # SPEC 14 positions columns (None where not resolved), K each
    motions: ErrorMotions
    lens: Any = None  # the lens-model check (:class:`lps_gui.pipeline.results.lens_model.LensModelCheck`)


def error_motion_results(sol: PoseSolution, targets_mm: np.ndarray, basis: str, tool: ToolPoint | None = None,
                         truth_rotations: np.ndarray | None = None, axis: str = "X",
                         lens: Any = None) -> ErrorMotionResults:
    """The ``error_motions`` section and the positions columns of one axis.

    ``truth_rotations`` (K, 3) rad: the simulator's carriage rotation vectors in the world frame,
    for the truth comparison of the angles (centred: the reference stop's own noise left out).
    """
    em = error_motions(sol, targets_mm, axis, **(tool.kwargs() if tool else {}), lens=lens)
    motions: dict[str, Any] = {}
    for name, iso in em.names.items():
        unit = UNITS[name]
        entry = {"motion": name, "unit": unit, "values": json_floats(em.values[name]),
                 "sigma": json_floats(em.sigmas[name]), "centred_sigma": json_floats(em.centred_sigmas[name]),
                 "median_centred_sigma": json_float(np.nanmedian(em.centred_sigmas[name])),
                 **em.profiles[name].to_dict(unit)}
        if name in ANGULAR:
            entry["single_view_sigma"] = json_floats(em.single_view_urad[:, ANGULAR.index(name)])
        motions[iso] = entry
    section: dict[str, Any] = {"basis": basis, "axis": axis, "reference_index": em.reference,
                               "frame_world": em.frame.tolist(), "motions": motions,
                               "resolved": {em.names[n]: em.resolved[n] for n in em.names}}
    if em.tool_positioning_um is not None:
        abbe = em.tool_positioning_um - em.values["positioning"]
        section["tool_point"] = {"offset_mm": list(tool.offset_mm), "frame": tool.frame,
                                 "offset_cam_mm": em.tool_cam_mm.tolist(),
                                 "positioning_um": json_floats(em.tool_positioning_um),
                                 "sigma_um": json_floats(em.tool_positioning_sigma_um),
                                 "abbe_um": json_floats(abbe), "max_abs_abbe_um": json_float(np.nanmax(np.abs(abbe)))}
    if truth_rotations is not None:
        section["truth"] = _truth(em, truth_rotations)
    columns: dict[str, list[Any]] = {}
    for name, stem in ANGLE_COLUMNS.items():
        keep = em.resolved[name]
        columns[f"{stem}_urad"] = json_floats(em.values[name]) if keep else [None] * len(em.values[name])
    for name, stem in ANGLE_COLUMNS.items():
        keep = em.resolved[name]
        columns[f"{stem}_sigma_urad"] = json_floats(em.sigmas[name]) if keep else [None] * len(em.values[name])
    return ErrorMotionResults(section, columns, em)


def _truth(em: ErrorMotions, w_world: np.ndarray) -> dict[str, Any]:
    """Per angle: the RMS error and mean (error/sigma)^2, both centred (a common offset is the reference's noise)."""
    used = np.isfinite(em.values["roll"])
    true = 1e6 * (w_world - w_world[em.reference]) @ em.frame  # (K, 3) urad about the estimate's X, Y, Z
    out: dict[str, Any] = {}
    for k, name in enumerate(ANGULAR):
        e = em.values[name][used] - true[used, k]
        e = e - e.mean()
        out[em.names[name]] = {"true_values": json_floats(np.where(used, true[:, k], np.nan)),
                               "rms_error_urad": json_float(np.sqrt(np.mean(e**2))),
                               "z_mean_square": json_float(np.mean((e / em.centred_sigmas[name][used]) ** 2))}
    return out


def board_truth_rotations(truth_meta: dict[str, Any] | None, truth: dict[str, Any] | None,
                          index: np.ndarray) -> np.ndarray | None:
    """A simulated session's carriage rotations (K, 3) rad in the world frame (the board's, or target
    0's), by capture index; None for a real session."""
    if not truth or not truth_meta or "angles_urad" not in truth:
        return None
    if not all(k in truth_meta for k in ("R_cam_board", "u_board")):
        return None
    F = motion_frame(np.asarray(truth_meta["R_cam_board"], float), np.asarray(truth_meta["u_board"], float))
    by_index = {int(i): a for i, a in zip(truth["index"], truth["angles_urad"])}
    if not all(int(i) in by_index for i in index):
        return None
    return 1e-6 * np.array([by_index[int(i)] for i in index]) @ F.T


def with_columns(row: dict[str, Any], columns: dict[str, list[Any]], i: int,
                 lens_sigma_um: float | None = None) -> dict[str, Any]:
    """A new position row: ``row`` with view ``i``'s values of ``columns`` and, when the lens misfit has one, its
    ``sigma_lens_um`` added in quadrature to ``sigma_total_um`` (``row`` itself untouched)."""
    out = {**row, **{key: values[i] for key, values in columns.items()}}
    if lens_sigma_um is not None:
        out["sigma_lens_um"] = json_float(lens_sigma_um)
        if out.get(SIGMA_TOTAL_UM) is not None:
            out[SIGMA_TOTAL_UM] = json_float(np.hypot(out[SIGMA_TOTAL_UM], lens_sigma_um))
    return out


def target_pose_solution(obs: Any, est: Any) -> tuple[PoseSolution, Any]:
    """Every stop's full pose against the session's targets, started from the row model's solution, and the
    intrinsics it was solved with (the lens check uses the same).

    Where the row self-calibrated, the poses are solved with both the calibrated and the self-calibrated
    intrinsics and the ones the poses fit better (lower a-posteriori sigma) are kept; neither adds a parameter
    to the pose model, so this is a plain choice of the likelier. Why both: the self-calibration frees the
    intrinsics inside the row model (one orientation for every stop). On a stage without angles it corrects
    the calibration, and the calibrated intrinsics fake tilts (the paper axis rendered, `lps demo --travel
    1524`, seeds 2-4: EBX and ECX called resolved, the poses fit 0.5-3.7 % worse in variance). On a stage
    with angles the freed intrinsics absorb the angular trend (a two-depth constellation's yaw of 120 urad
    over 600 mm came out 66 urad, mean (error/sigma)^2 9.4), and the calibrated ones fit the poses better.
    """
    from lps_gui.core.models.pose_model import solve_poses
    from lps_gui.core.models.target_model import TargetObservations

    tobs = TargetObservations(list(obs.mounted), obs.corners_px, obs.targets, list(obs.names))
    start = getattr(est, "fit_targets", None) if obs.D == 2 else getattr(est, "fit", None)  # the row model's solution
    if start is not None and not (start.converged and start.sigma_px < WARM_START_MAX_PX):
        start = None  # a row model that did not fit these views is no start: per-view PnP instead
    held = solve_poses(tobs, obs.intrinsics, start=start)
    refined = getattr(getattr(est, "state", None), "intrinsics", None)
    if refined is None or refined is obs.intrinsics or np.array_equal(refined.vector(), obs.intrinsics.vector()):
        return held, obs.intrinsics
    other = solve_poses(tobs, refined, start=start)
    return (other, refined) if other.sigma_px < held.sigma_px else (held, obs.intrinsics)


def with_estimated_bows(obs: Any, est: Any) -> Any:
    """``obs`` with its targets bowed as the estimate found them (core/models/target_model.bow_columns), so the
    poses and the lens check see the prints as they are: a bow left out shows as a lens misfit and fake tilts."""
    from dataclasses import replace

    from lps_gui.core.models.target_model import with_bows

    bows = getattr(getattr(est, "fit_targets", None), "bows_mm", None)
    return obs if bows is None else replace(obs, mounted=with_bows(list(obs.mounted), bows))


def session_error_motions(meta: dict[str, Any], where: str, obs: Any, est: Any,
                          truth: dict[str, Any] | None) -> ErrorMotionResults | None:
    """A line session's error motions: from the full poses against its targets, or a single board's
    6-DOF poses (None when the method has none)."""
    tool = tool_point(meta, where)
    if obs.mounted is not None:
        obs = with_estimated_bows(obs, est)
        (sol, intrinsics), basis = target_pose_solution(obs, est), BASIS_TARGETS
    else:
        sol, intrinsics, basis = board_pose_solution(est), obs.intrinsics, BASIS_BOARD
    if sol is None or int(np.asarray(sol.used).sum()) < 3:
        return None
    from lps_gui.pipeline.results.lens_model import lens_model_check, lens_terms, position_lens_sigma_um

    w = board_truth_rotations(meta.get("truth"), truth, np.asarray(obs.index))
    check = lens_model_check(sol, obs, intrinsics)
    out = error_motion_results(sol, obs.target_mm, basis, tool, w, lens=lens_terms(check, sol, obs.intrinsics))
    if check.misfit is not None:
        check.position_sigma_um = position_lens_sigma_um(sol, obs, check.misfit, out.motions.frame,
                                                         out.motions.reference)
    out.lens = check
    return out


def planar_error_motion_results(sol: PoseSolution, targets_mm: np.ndarray,
                                truth_rotations: np.ndarray | None = None, lens: Any = None) -> ErrorMotionResults:
    """A planar stage's section: both axes' six error motions over their own positions, the per-stop angles
    about the stage X, Y, Z (positions.csv, empty where neither axis' motion about it is resolved)."""
    pm = planar_error_motions(sol, targets_mm, lens)
    motions: dict[str, Any] = {}
    for name, along, kind, _ in PLANAR_MOTIONS:
        unit = "urad" if kind == "angle" else "um"
        motions[name] = {"motion": kind, "along": "XY"[along], "unit": unit,
                         "positions_mm": json_floats(pm.axis_positions[along]), "values": json_floats(pm.values[name]),
                         "sigma": json_floats(pm.sigmas[name]), "centred_sigma": json_floats(pm.centred_sigmas[name]),
                         "median_centred_sigma": json_float(np.nanmedian(pm.centred_sigmas[name])),
                         **pm.profiles[name].to_dict(unit)}
    section: dict[str, Any] = {"basis": BASIS_TARGETS, "axes": ["X", "Y"], "reference_index": pm.reference,
                               "frame_world": pm.frame.tolist(), "motions": motions, "resolved": dict(pm.resolved)}
    if truth_rotations is not None:
        used = np.isfinite(pm.per_stop_urad[:, 0])
        true = 1e6 * (truth_rotations - truth_rotations[pm.reference]) @ pm.frame
        truth = {}
        for name, along, kind, comp in PLANAR_MOTIONS:
            if kind != "angle":
                continue
            tv = pm.weights[name] @ np.where(used, true[:, comp], 0.0)
            e = pm.values[name] - tv
            e = e - e.mean()
            truth[name] = {"true_values": json_floats(tv), "rms_error_urad": json_float(np.sqrt(np.mean(e**2))),
                           "z_mean_square": json_float(np.mean((e / pm.centred_sigmas[name]) ** 2))}
        section["truth"] = truth
    columns: dict[str, list[Any]] = {}
    about = {0: ("EAX", "EAY"), 1: ("EBX", "EBY"), 2: ("ECX", "ECY")}
    for kind, per_stop in (("urad", pm.per_stop_urad), ("sigma_urad", pm.per_stop_sigma_urad)):  # values, then sigmas
        for comp, name in enumerate(PLANAR_ANGLE_NAMES):
            keep = any(pm.resolved[n] for n in about[comp])
            columns[f"{name.lower()}_{kind}"] = json_floats(per_stop[:, comp]) if keep else [None] * len(per_stop)
    return ErrorMotionResults(section, columns, pm)


def planar_truth_rotations(truth_meta: dict[str, Any] | None, index: np.ndarray) -> np.ndarray | None:
    """A simulated gantry's carriage rotations (K, 3) rad in the world frame (session.json truth, by capture index)."""
    if not truth_meta or "angles_urad" not in truth_meta or "axes_board" not in (truth_meta.get("rig") or {}):
        return None
    angles = np.asarray(truth_meta["angles_urad"], float)
    if angles.ndim != 2 or angles.shape[1] != 3 or not np.all((index >= 0) & (index < len(angles))):
        return None
    return 1e-6 * angles[index] @ np.asarray(truth_meta["rig"]["axes_board"], float).T


@dataclass(frozen=True)
class ErrorMotionsOutcome:
    """What the error motions give the results, as new values (the rows, figures and flags passed in untouched):
    the section, the position rows with SPEC 14's columns (and the lens misfit's sigma), the figures with the
    angles' findings as the profiles resolve them, the flags with the lens check's."""

    section: dict[str, Any]  # results.json ``error_motions``, written through its reader (ErrorMotionsSection)
    positions: list[dict[str, Any]]
    figures: dict[str, Any]
    flags: list[dict[str, Any]]


def session_motions(session: Any, obs: Any, est: Any) -> ErrorMotionResults | None:
    """The error motions of a session where the poses allow (None otherwise).

    A line: from the targets' joint pose solve or a single board's 6-DOF poses; a plane: from the
    targets' joint pose solve (a single board's planar fit keeps one orientation and has no per-view poses).
    """
    meta, where = session.meta, str(session.folder / "session.json")
    if obs.segment is not None:
        return None  # one board moved between segments: its placements are tied by repeated stops, never seen together
    if obs.D == 1:
        return session_error_motions(meta, where, obs, est, session.truth)
    if obs.mounted is None:
        return None
    tool_point(meta, where)  # checked alike, used by one axis only
    obs = with_estimated_bows(obs, est)
    sol, intrinsics = target_pose_solution(obs, est)
    w = planar_truth_rotations(meta.get("truth"), np.asarray(obs.index))
    if int(sol.used.sum()) < 3:
        return None
    from lps_gui.pipeline.results.lens_model import lens_model_check, lens_terms

    check = lens_model_check(sol, obs, intrinsics)
    motions = planar_error_motion_results(sol, obs.target_mm, w, lens=lens_terms(check, sol, obs.intrinsics))
    motions.lens = check
    return motions


def error_motions_outcome(session: Any, obs: Any, est: Any, positions: list[dict[str, Any]], figures: dict[str, Any],
                          flags: list[dict[str, Any]]) -> ErrorMotionsOutcome | None:
    """results.json ``error_motions`` and the new positions, figures and flags it makes, where the poses allow
    (None otherwise: the results keep the values they have)."""
    motions = session_motions(session, obs, est)
    if motions is None:
        return None
    section = dict(motions.section)
    lens_um = None
    if motions.lens is not None:
        section["lens_model"] = motions.lens.section
        flags = [*flags, *motions.lens.flags]
        lens_um = motions.lens.position_sigma_um
        if lens_um is not None and len(positions) != len(lens_um):  # the positions carry the lens misfit
            lens_um = None
    positions = [with_columns(row, motions.columns, i, None if lens_um is None else lens_um[i])
                 for i, row in enumerate(positions)]
    if obs.D == 1 and figures.get("angles_resolution"):  # "Max |roll|" is a finding only if EAX's profile is
        names = iso_names(section.get("axis", "X"))
        verdicts = section.get("resolved") or {}
        figures = {**figures, "angles_resolution": with_profile_resolution(
            figures["angles_resolution"], {a: bool(verdicts.get(names[a], True)) for a in ANGULAR})}
    return ErrorMotionsOutcome(ErrorMotionsSection.of(**section).to_dict(), positions, figures, list(flags))
