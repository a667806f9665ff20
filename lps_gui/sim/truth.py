"""The simulator's ground truth: written, read (one rule) and compared with a measurement (one reduction).

Where truth lives
    The point and image simulators know every pose up front and store it in
    session.json's ``truth`` (``index``, ``axis_mm``, ``positions_mm``,
    ``straightness_um`` (K, 2), ``angles_urad`` (K, 3), in capture-index
    order; the layout of :func:`core.simulate.true_views`); a planar session's
    (D = 2, SPEC 10) ``plane_mm`` (K, 2) and ``board_plane_mm`` (K, 2). A capture on the
    simulated rig learns it as the stage moves: :class:`TruthRecorder` appends
    one line per frame to :data:`TRUTH_FILE` (durably, before the frame's
    capture line, so every listed frame has its truth) and, once the plan is
    complete, folds it into session.json in the same layout.

The one reading rule
    A resumed capture may have appended a line twice for one index, or a crash
    may have torn the last line: the last complete line per index wins, a torn
    line is ignored (:func:`read_truth`). :func:`session_truth` gives the same
    arrays whichever of the two places holds the truth.

The one reference convention (SPEC section 5: offset zero at the first capture)
    A stage measurement is relative: the estimate fixes its gauge at the
    *reference capture*, the first capture whose board was found and which is
    not an outlier (the first capture of the session unless it is unusable).
    Truth is put in the same frame: measured and true coordinates are both
    taken relative to that capture, so the error there is zero by construction
    and every other error is ``(measured - measured[ref]) - (true - true[ref])``.
    :func:`reduce_truth` does this for coordinates of shape (K, D) (D = 1 on a
    linear stage, 2 on a planar one, SPEC section 10); results.json's
    ``truth_comparison``, the report's truth curves, the GUI and ``lps demo``'s
    printed line all come from it. Truth straightness is put relative to its
    least-squares line over the compared views (as the estimate's is) and truth
    angles relative to their mean (as the estimate's are, to the common R).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from lps_gui.core.estimator.estimate_types import LpsEstimate
from lps_gui.core.estimator.observations import Observations
from lps_gui.core.geometry.camera_model import project_board
from lps_gui.core.metrology.planar_figures import axis_geometry, planar_figures
from lps_gui.core.models.planar_model import affine_motion, planar_positions_only, planar_truth_in_stage_frame
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.simulate import board_plane_positions, board_plane_straightness, nominal_planar_state
from lps_gui.core.truth.stage_errors import PlanarTruePose, StageErrorModel, TruePose
from lps_gui.errors import InputError
from lps_gui.io.atomic import append_line_durable, write_text_atomic
from lps_gui.io.board_file import board_from_dict
from lps_gui.io.intrinsics_file import intrinsics_from_dict
from lps_gui.io.results.document import json_float as _f
from lps_gui.io.results.document import json_floats
from lps_gui.io.session import Session
from lps_gui.io.session_paths import read_session_file

TRUTH_FILE = "truth.jsonl"
MAX_TRUTH_BYTES = 256 << 20  # ~300 bytes a capture
ANGLE_NAMES = ("roll", "pitch", "yaw")


# ----------------------------------------------------------------------------- write (capture on the simulated rig)


def pose_truth(pose: TruePose) -> dict[str, Any]:
    """A one-carriage :class:`TruePose` (K=1) as a JSON-able dict."""
    return {
        "axis_mm": float(pose.axis_mm.ravel()[0]),
        "straightness_um": [float(v) for v in pose.straightness_um.reshape(-1)[:2]],
        "angles_urad": [float(v) for v in pose.angles_urad.reshape(-1)[:3]],
    }


def planar_pose_truth(rig: Rig, pose: PlanarTruePose) -> dict[str, Any]:
    """A gantry's carriage pose (K=1) as a JSON-able dict; beside the true plane position the board-plane
    position (what a constant-orientation model sees when the carriage tilts), so the comparison needs no
    re-projection later."""
    R, t = rig.camera_poses(pose)
    X = rig.board.object_points()
    uv = project_board(R, t, X, rig.intrinsics)
    board_plane = planar_positions_only(nominal_planar_state(rig, pose.plane_mm), X, uv, np.ones(uv.shape[:2], bool))
    return {
        "plane_mm": [float(v) for v in pose.plane_mm[0]],
        "board_plane_mm": [float(v) for v in board_plane[0]],
        "normal_um": float(pose.normal_um[0]),
        "angles_urad": [float(v) for v in pose.angles_urad[0]],
    }


def append_truth(session: Session, index: int, truth: dict[str, Any]) -> None:
    """Append the truth of capture ``index`` to truth.jsonl (fsynced)."""
    line = json.dumps({"index": int(index), **truth}, separators=(",", ":"))
    session.check_present()
    append_line_durable(session.folder / TRUTH_FILE, line)


def read_truth(session: Session) -> dict[int, dict[str, Any]]:
    """Truth per capture index from truth.jsonl (last line per index wins; a torn line is ignored)."""
    path = session.folder / TRUTH_FILE
    if not path.exists():
        return {}
    out: dict[int, dict[str, Any]] = {}
    try:  # inside the session, a regular file, size-capped (never /dev/zero through a link)
        text = read_session_file(session.folder, TRUTH_FILE, MAX_TRUTH_BYTES, "truth file").decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (binary content); regenerate the session") from None
    for line in text.splitlines():
        try:
            d = json.loads(line)
            out[int(d["index"])] = d
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            continue  # a crash tore it; the capture it belongs to was not listed
    return out


def prune_truth(session: Session) -> None:
    """Keep only the truth lines of listed captures (once each): run before a capture (re)starts.

    A crash between a frame's truth line and its capture line leaves a line
    for a frame that is not listed (or a torn one); the resumed capture
    takes that frame again, so without pruning its index would appear twice.
    """
    path = session.folder / TRUTH_FILE
    if not path.exists():
        return
    listed = {r.index for r in session.records()}
    per_index = read_truth(session)
    keep = [per_index[i] for i in sorted(per_index) if i in listed]
    text = "".join(json.dumps(d, separators=(",", ":")) + "\n" for d in keep)
    if text.encode("utf-8") != read_session_file(session.folder, TRUTH_FILE, MAX_TRUTH_BYTES, "truth file"):
        write_text_atomic(path, text)


def finalize_truth(session: Session) -> None:
    """Write the per-capture truth of every listed capture into session.json's ``truth``."""
    per_index = read_truth(session)
    indices = sorted({r.index for r in session.records()} & set(per_index))
    if not indices:
        return
    rows = [per_index[i] for i in indices]
    truth = dict(session.meta.get("truth") or {})
    if "plane_mm" in rows[0]:  # a gantry's (SPEC 10)
        truth.update({"index": indices, "plane_mm": [r["plane_mm"] for r in rows],
                      "board_plane_mm": [r["board_plane_mm"] for r in rows],
                      "normal_um": [r["normal_um"] for r in rows], "angles_urad": [r["angles_urad"] for r in rows]})
        session.meta["truth"] = truth
        session.save_meta()
        return
    axis = [float(r["axis_mm"]) for r in rows]
    truth.update(
        {
            "index": indices,
            "axis_mm": axis,
            "positions_mm": [a - axis[0] for a in axis],
            "straightness_um": [list(r["straightness_um"]) for r in rows],
            "angles_urad": [list(r["angles_urad"]) for r in rows],
        }
    )
    session.meta["truth"] = truth
    session.save_meta()


class TruthRecorder:
    """The capture engine's truth hook on the simulated rig: the pose the camera renders, per frame.

    ``rig``: a gantry's :class:`Rig` (its rows also hold the board-plane
    position, :func:`planar_pose_truth`); None on one axis.
    """

    def __init__(self, pose_source: Callable[[], Any], rig: Rig | None = None) -> None:
        self.pose_source = pose_source
        self.rig = rig

    def prune(self, session: Session) -> None:
        prune_truth(session)

    def record(self, session: Session, index: int) -> None:
        pose = self.pose_source()
        append_truth(session, index, pose_truth(pose) if self.rig is None else planar_pose_truth(self.rig, pose))

    def finalize(self, session: Session) -> None:
        finalize_truth(session)


# ----------------------------------------------------------------------------- read


def session_truth(session: Session) -> dict[str, Any] | None:
    """Arrays index (K,), axis_mm (K,), straightness_um (K, 2), angles_urad (K, 3), or None for a real session;
    a planar session's (D = 2): index, plane_mm (K, 2), board_plane_mm (K, 2) (:func:`_plane_truth`).

    truth.jsonl wins over session.json (it is the newer record while a capture
    is incomplete). With the rig's geometry recorded, also ``plane_mm`` (K,):
    the positions a constant-orientation model sees (core.simulate.board_plane_positions).
    A truth that is not numbers of those shapes is an InputError naming the files.
    """
    try:
        out = _session_truth(session)
    except (TypeError, ValueError, KeyError, IndexError) as exc:
        raise InputError(f"{session.folder}: the simulator's truth (session.json 'truth' or {TRUTH_FILE}) is not "
                         f"numbers of the expected shape ({str(exc)[:80]}); regenerate the session") from None
    if out is not None and not all(np.all(np.isfinite(out[k])) for k in ("axis_mm", "straightness_um", "angles_urad")
                                   if k in out):
        raise InputError(f"{session.folder}: the simulator's truth holds non-finite values; regenerate the session")
    return out


def _session_truth(session: Session) -> dict[str, Any] | None:
    if session.planar:
        return _plane_truth(session)
    meta = session.meta.get("truth") or {}
    per_index = read_truth(session)
    if per_index:
        lines = [per_index[i] for i in sorted(per_index)]
        out: dict[str, Any] = {
            "index": np.array([l["index"] for l in lines], dtype=int),
            "axis_mm": np.array([l["axis_mm"] for l in lines], dtype=float),
        }
        if all("straightness_um" in l for l in lines):
            out["straightness_um"] = np.array([l["straightness_um"] for l in lines], dtype=float).reshape(-1, 2)
        if all("angles_urad" in l for l in lines):
            out["angles_urad"] = np.array([l["angles_urad"] for l in lines], dtype=float).reshape(-1, 3)
    elif meta.get("axis_mm") is not None:
        K = len(meta["axis_mm"])
        out = {"index": np.array(meta.get("index", range(K)), dtype=int), "axis_mm": np.asarray(meta["axis_mm"], dtype=float)}
        if meta.get("straightness_um") is not None:
            out["straightness_um"] = np.asarray(meta["straightness_um"], dtype=float).reshape(K, 2)
        if meta.get("angles_urad") is not None:
            out["angles_urad"] = np.asarray(meta["angles_urad"], dtype=float).reshape(K, 3)
    else:
        return None
    out["replaced_views"] = meta.get("replaced_views", [])
    out["bumped_views"] = meta.get("bumped_views", [])
    plane = _board_plane(session, meta, out)
    if plane is not None:
        out["plane_mm"], out["plane_straightness_um"], out["image_rotation_urad"] = plane
    return out


def _board_plane(session: Session, meta: dict[str, Any], truth: dict[str, Any]
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """What a constant-orientation model sees of the true poses: positions at the board plane (K,),
    straightness at the board plane (K, 2) um and the rotation about the optical axis (K,) urad."""
    if not all(k in meta for k in ("R_cam_board", "C0_board", "u_board")):
        return None
    K = truth["axis_mm"].size
    board = board_from_dict(meta["board"]) if "board" in meta else session.board()
    intr = intrinsics_from_dict(meta["intrinsics"]) if "intrinsics" in meta else session.intrinsics()
    rig = Rig(board, intr, np.asarray(meta["R_cam_board"], float), np.asarray(meta["C0_board"], float),
              np.asarray(meta["u_board"], float), StageErrorModel())
    pose = TruePose(truth["axis_mm"], truth.get("straightness_um", np.zeros((K, 2))), truth.get("angles_urad", np.zeros((K, 3))))
    return (board_plane_positions(rig, pose), *board_plane_straightness(rig, pose))


# ----------------------------------------------------------------------------- reduce


@dataclass(frozen=True)
class TruthReduction:
    """Measured minus true coordinates, both relative to the reference capture (module docstring)."""

    error_um: np.ndarray  # (K, D); row ``reference`` is zero
    compared: np.ndarray  # (K,) bool: the views the figures below are taken over
    rms_um: float | None  # RMS over compared views of the error vector's length
    max_abs_um: float | None  # largest error vector length
    z_mean_square: float | None  # mean of (error / sigma)^2 over compared views but the reference (expect ~1)


def _as_kd(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return x[:, None] if x.ndim == 1 else x


def reduce_truth(
    measured_mm: np.ndarray,
    true_mm: np.ndarray,
    reference: int,
    compared: np.ndarray,
    sigma_um: np.ndarray | None = None,
) -> TruthReduction:
    """The one comparison of a measurement with the simulator's truth.

    Parameters
    ----------
    measured_mm, true_mm : (K,) or (K, D) coordinates per view in mm, in any
        origin (each is taken relative to its own row ``reference``).
    reference : the reference capture's view (the estimate's gauge view).
    compared : (K,) bool, the views to take figures over (used and with truth).
    sigma_um : (K,) or (K, D) 1-sigma of the measured coordinates in um (the unit of the position rows), for the
        z test.
    """
    m, t = _as_kd(measured_mm), _as_kd(true_mm)
    err = 1e3 * ((m - m[reference]) - (t - t[reference]))
    ok = np.asarray(compared, dtype=bool)
    lengths = np.sqrt(np.sum(err[ok] ** 2, axis=1))
    z_ms = None
    if sigma_um is not None:
        others = ok & (np.arange(err.shape[0]) != reference)
        z = err[others] / np.maximum(_as_kd(sigma_um)[others], 1e-12)
        z = z[np.isfinite(z)]
        z_ms = float(np.mean(z**2)) if z.size else None
    return TruthReduction(
        error_um=err,
        compared=ok,
        rms_um=_f(np.sqrt(np.mean(lengths**2))) if lengths.size else None,
        max_abs_um=_f(np.max(lengths)) if lengths.size else None,
        z_mean_square=z_ms,
    )


def residual_from_line(values: np.ndarray, coord_mm: np.ndarray, fit: np.ndarray) -> np.ndarray:
    """``values`` (K, P) minus their least-squares line in ``coord_mm`` (K,) or plane in (K, D), fitted on ``fit``."""
    c = _as_kd(coord_mm)
    design = np.concatenate([np.ones((c.shape[0], 1)), c], axis=1)  # shape (K, 1 + D)
    coef = np.linalg.lstsq(design[fit], values[fit], rcond=None)[0]
    return values - design @ coef


def true_deviation_um(true_mm: np.ndarray, target_mm: np.ndarray, reference: int) -> np.ndarray:
    """The simulator's positioning error per view in um: true minus nominal travel from the reference capture."""
    t, g = np.asarray(true_mm, dtype=float), np.asarray(target_mm, dtype=float)
    return 1e3 * ((t - t[reference]) - (g - g[reference]))


def centred(values: np.ndarray, compared: np.ndarray) -> np.ndarray:
    """``values`` (K, P) minus their mean over the compared views (angles: relative to the common rotation)."""
    return values - np.mean(values[compared], axis=0)


def truth_comparison(obs: Observations, est: LpsEstimate, truth: dict[str, Any], positions: list[dict],
                     out_of_plane: tuple[np.ndarray, np.ndarray] | None = None,
                     drawn_sigma_um: np.ndarray | None = None) -> tuple[dict[str, Any], list[dict]]:
    """results.json ``truth_comparison`` (schema in docs/ARCHITECTURE.md) and the position rows with truth beside
    each: new rows, ``positions`` is left as it was (a builder returns values, issue 34).

    Everything here goes through :func:`reduce_truth` with the estimate's
    reference capture, so the numbers are the ones the report, the GUI and
    ``lps demo`` show. A planar estimate (D = 2) is compared by :func:`_plane_truth_comparison`, its out-of-plane
    displacement and sigma per capture (um) given as ``out_of_plane`` (values, not read back from the rows).
    On a line the per-stop z test scores ``drawn_sigma_um`` (K,): the sigma the bands draw, positions.csv's
    ``sigma_total_um`` once the error motions have folded the lens misfit in (the caller compares after them,
    pipeline/estimate.build_results); without it, the estimate's own sigma_total.
    """
    if est.D == 2:
        return _plane_truth_comparison(obs, est, truth, positions, out_of_plane)
    by_index = {int(i): k for k, i in enumerate(truth["index"])}
    rows = np.array([by_index.get(int(i), -1) for i in obs.index])
    have = rows >= 0
    ref = est.reference_view
    if not have[ref]:
        return {"note": "truth does not cover the reference capture"}, list(positions)
    take = np.maximum(rows, 0)
    ok = est.used & have

    def per_view(values: np.ndarray) -> np.ndarray:
        v = np.asarray(values, dtype=float)[take]
        v[~have] = np.nan
        return v

    axis = per_view(truth["axis_mm"])
    drawn = 1e3 * est.sigma_total_mm if drawn_sigma_um is None else np.asarray(drawn_sigma_um, dtype=float)
    pos = reduce_truth(est.state.s, axis, ref, ok, drawn)
    true_dev = true_deviation_um(axis, obs.target_mm, ref)
    sigma_um = 1e3 * est.sigma_total_mm[ok]  # the estimate's own (the lens misfit's share is in the z test only)
    out: dict[str, Any] = {
        "position_rms_error_um": pos.rms_um,
        "position_max_abs_error_um": pos.max_abs_um,
        "mean_sigma_um": _f(np.nanmean(sigma_um)) if sigma_um.size else None,
        "median_sigma_um": _f(np.nanmedian(sigma_um)) if sigma_um.size else None,
        "z_mean_square": pos.z_mean_square,
        "injected_outliers": sorted(set(truth.get("replaced_views", [])) | set(truth.get("bumped_views", []))),
        "flagged_outliers": sorted(int(i) for i in obs.index[est.outlier]),
    }
    # the estimate's straightness is relative to a least-squares line and its angles to the common rotation
    straight = truth.get("plane_straightness_um", truth.get("straightness_um"))  # at the board plane (SPEC 11)
    straight = residual_from_line(per_view(straight), obs.target_mm, ok) if straight is not None and ok.any() else None
    angles = truth.get("angles_urad")
    angles = centred(per_view(angles), ok) if angles is not None and ok.any() else None
    plane_dev = None
    if "plane_mm" in truth:
        # what the constant-orientation model can see: displacement at the board plane (Abbe offset = distance)
        plane = per_view(truth["plane_mm"])
        at_plane = reduce_truth(est.state.s, plane, ref, ok, drawn)
        out["board_plane_rms_error_um"] = at_plane.rms_um
        out["board_plane_max_abs_error_um"] = at_plane.max_abs_um
        out["board_plane_z_mean_square"] = at_plane.z_mean_square
        out["abbe_rms_um"] = reduce_truth(plane, axis, ref, ok).rms_um
        plane_dev = true_deviation_um(plane, obs.target_mm, ref)
    rotation = truth.get("image_rotation_urad")
    rotation = per_view(rotation) if rotation is not None else None
    out.update(truth_errors(est, straight, rotation, ok))
    columns = {"truth_deviation_um": true_dev}  # per position, beside the estimate (views with truth only)
    if rotation is not None and ok.any():
        columns["truth_image_rotation_urad"] = rotation - np.nanmean(rotation[ok])
    if plane_dev is not None:
        columns["truth_plane_deviation_um"] = plane_dev
    if straight is not None:
        columns["truth_straightness_um_1"], columns["truth_straightness_um_2"] = straight[:, 0], straight[:, 1]
    if angles is not None:
        for j, key in enumerate(ANGLE_NAMES):
            columns[f"truth_{key}_urad"] = angles[:, j]
    keys = list(columns)
    values = list(zip(*(json_floats(v) for v in columns.values())))
    return out, [{**row, **(dict(zip(keys, values[k])) if have[k] else {})} for k, row in enumerate(positions)]


def truth_errors(est: LpsEstimate, straight_truth: np.ndarray | None, rotation_truth: np.ndarray | None,
                 ok: np.ndarray) -> dict[str, Any]:
    """RMS error and mean (error/sigma)^2 of v1, v2 and the image rotation against simulator truth.

    ``straight_truth`` (K, 2) is already relative to its least-squares line,
    ``rotation_truth`` (K,) per view; the image rotation is compared with both
    means removed (the common R absorbs a constant rotation).
    """
    bp = est.board_plane
    out: dict[str, Any] = {}
    if bp is None:
        return out
    if straight_truth is not None:
        for j in (0, 1):
            keep = ok & np.isfinite(straight_truth[:, j]) & np.isfinite(bp.straightness_um[:, j])
            if keep.sum() < 3:
                continue
            err = bp.straightness_um[keep, j] - straight_truth[keep, j]
            out[f"straightness_rms_error_um_{j + 1}"] = _f(np.sqrt(np.mean(err**2)))
            out[f"straightness_z_mean_square_{j + 1}"] = _f(np.mean((err / bp.straightness_sigma_um[keep, j]) ** 2))
    if rotation_truth is not None:
        keep = ok & np.isfinite(rotation_truth) & np.isfinite(bp.image_rotation_urad)
        if keep.sum() >= 3:
            e = bp.image_rotation_urad[keep] - rotation_truth[keep]
            e = e - e.mean()
            out["image_rotation_rms_error_urad"] = _f(np.sqrt(np.mean(e**2)))
            out["image_rotation_z_mean_square"] = _f(np.mean((e / bp.image_rotation_sigma_urad[keep]) ** 2))
    return out


# ----------------------------------------------------------------------------- D = 2: a planar session (SPEC 10)


def _plane_truth(session: Session) -> dict[str, Any] | None:
    """A planar session's truth: index (K,), plane_mm (K, 2), board_plane_mm (K, 2), or None for a real session."""
    meta = dict(session.meta.get("truth") or {})
    per_index = read_truth(session)  # a capture on the simulated gantry: newer than session.json while incomplete
    if per_index and all("plane_mm" in r for r in per_index.values()):
        rows = [per_index[i] for i in sorted(per_index)]
        meta.update(index=[r["index"] for r in rows], plane_mm=[r["plane_mm"] for r in rows],
                    board_plane_mm=[r["board_plane_mm"] for r in rows])
        if all("normal_um" in r and "angles_urad" in r for r in rows):
            meta.update(normal_um=[r["normal_um"] for r in rows], angles_urad=[r["angles_urad"] for r in rows])
    if meta.get("plane_mm") is None:
        return None
    K = len(meta["plane_mm"])
    out: dict[str, Any] = {
        "index": np.array(meta.get("index", range(K)), dtype=int),
        "plane_mm": np.asarray(meta["plane_mm"], dtype=float).reshape(K, 2),
        "replaced_views": meta.get("replaced_views", []),
        "bumped_views": meta.get("bumped_views", []),
    }
    if meta.get("board_plane_mm") is not None:
        out["board_plane_mm"] = np.asarray(meta["board_plane_mm"], dtype=float).reshape(K, 2)
    squareness = ((meta.get("rig") or {}).get("stage_errors") or {}).get("squareness_urad")
    if squareness is not None:
        out["squareness_urad"] = float(squareness)
    normal = _board_plane_normal_um(meta, out["plane_mm"], K)
    if normal is not None:
        out["board_plane_normal_um"] = normal
    return out


def _board_plane_normal_um(meta: dict[str, Any], plane_mm: np.ndarray, K: int) -> np.ndarray | None:
    """Where a constant-orientation model sees each true pose along the plane normal, at the board centre (um).

    The carriage's out-of-plane displacement plus what its rotation w does at
    the board: D = C + w x (X0 - C) (core.constant_orientation.board_plane_offsets,
    first order in w, no solver), projected on the stage's normal e_n.
    """
    rig, board = meta.get("rig") or {}, meta.get("board")
    if meta.get("normal_um") is None or meta.get("angles_urad") is None or not rig or not board:
        return None
    from lps_gui.core.models.constant_orientation import board_plane_offsets
    from lps_gui.io.board_file import board_from_dict

    E = np.asarray(rig["axes_board"], float)
    C0 = np.asarray(rig["C0_board"], float)
    normal = np.asarray(meta["normal_um"], float).reshape(K)
    C = C0[None, :] + plane_mm @ E[:, :2].T + 1e-3 * normal[:, None] * E[None, :, 2]
    w = 1e-6 * np.asarray(meta["angles_urad"], float).reshape(K, 3) @ E.T
    X0 = board_from_dict(board, "session.json truth").object_points().mean(axis=0)
    return 1e3 * (board_plane_offsets(C, w, X0) - C0[None, :]) @ E[:, 2]


def _plane_true_xy(obs: Observations, est: LpsEstimate, truth: dict[str, Any]
                   ) -> tuple[np.ndarray, np.ndarray, str, np.ndarray] | None:
    """The true planar positions in the estimate's frame (SPEC 10) with the truth rows of the captures, the views
    compared and the truth key used; None when truth does not cover every capture."""
    by_index = {int(i): k for k, i in enumerate(truth["index"])}
    rows = np.array([by_index.get(int(i), -1) for i in obs.index])
    have = rows >= 0
    if not have.all():
        return None
    ok = est.used & have
    key = "board_plane_mm" if "board_plane_mm" in truth else "plane_mm"
    true_xy = planar_truth_in_stage_frame(truth[key][rows], obs.target_mm, obs.approach, ok, est.reference_view)
    return rows, ok, key, true_xy


def plane_true_deviation_um(obs: Observations, est: LpsEstimate, truth: dict[str, Any]) -> np.ndarray:
    """(K, 2) true deviation of every capture of a planar session, NaN where not compared: the value the
    builder's error map puts beside the measured one (the truth columns of the position rows hold the same)."""
    plane = _plane_true_xy(obs, est, truth)
    if plane is None:
        return np.full((obs.K, 2), np.nan)
    return true_deviation_um(plane[3], obs.target_mm, est.reference_view)


def _plane_truth_comparison(obs: Observations, est: LpsEstimate, truth: dict[str, Any], positions: list[dict],
                            out_of_plane: tuple[np.ndarray, np.ndarray] | None) -> tuple[dict[str, Any], list[dict]]:
    """results.json ``truth_comparison`` of a planar session and new position rows with truth beside each.

    Truth is put in the estimate's frame convention first (SPEC 10: origin at the reference capture, +x along
    the fitted +X motion), by the rule the estimator applies to its own positions
    (:func:`lps_gui.core.models.planar_model.planar_truth_in_stage_frame`).
    """
    plane = _plane_true_xy(obs, est, truth)
    if plane is None:
        return {"note": "truth does not cover every capture"}, list(positions)
    rows, ok, key, true_xy = plane
    ref = est.reference_view
    pos = reduce_truth(est.state.xy, true_xy, ref, ok, 1e3 * est.sigma_s_mm)
    sig = 1e3 * est.sigma_s_mm[ok]
    true_geo = axis_geometry(affine_motion(true_xy, obs.target_mm, obs.approach, ok), np.zeros((4, 4)))
    geo = axis_geometry(est.fit.G, est.fit.cov_G)
    out: dict[str, Any] = {
        "reference": "board plane" if key == "board_plane_mm" else "carriage",
        "position_rms_error_um": pos.rms_um,
        "position_max_abs_error_um": pos.max_abs_um,
        "per_coordinate_rms_error_um": [_f(v) for v in np.sqrt(np.mean(pos.error_um[ok] ** 2, axis=0))],
        "mean_sigma_um": _f(np.sqrt(np.mean(sig**2))) if sig.size else None,
        "z_mean_square": pos.z_mean_square,
        "squareness_urad": true_geo.squareness_urad,
        "squareness_error_urad": geo.squareness_urad - true_geo.squareness_urad,
        "squareness_z": (geo.squareness_urad - true_geo.squareness_urad) / max(geo.squareness_sigma_urad, 1e-12),
        "scale_x_ppm": true_geo.scale_x_ppm,
        "scale_x_error_ppm": geo.scale_x_ppm - true_geo.scale_x_ppm,
        "scale_y_ppm": true_geo.scale_y_ppm,
        "scale_y_error_ppm": geo.scale_y_ppm - true_geo.scale_y_ppm,
        "injected_outliers": sorted(set(truth.get("replaced_views", [])) | set(truth.get("bumped_views", []))),
        "flagged_outliers": sorted(int(i) for i in obs.index[est.outlier]),
    }
    if "squareness_urad" in truth:
        out["model_squareness_urad"] = truth["squareness_urad"]
    true_dev = true_deviation_um(true_xy, obs.target_mm, ref)
    # the same per-line reduction as the estimate's; the truth has no noise to take out (a sigma of 1 pm, not 0:
    # the straightness test divides by it)
    true_figs = planar_figures(obs.target_mm, obs.approach, obs.run, obs.direction, true_dev, np.full_like(true_dev, 1e-6),
                               ok, np.eye(2), np.zeros((4, 4)))
    for axis in ("X", "Y"):
        true_axis = true_figs.per_axis.get(axis) or {}
        out[f"straightness_{axis.lower()}_um"] = true_axis.get("straightness_um_max")
        iso = ((true_axis.get("iso230_2") or {}).get("iso230_2")) or {}
        if iso:  # the ISO 230-2 figures of the true deviations, by the estimate's per-line rule
            out[f"iso230_2_{axis.lower()}"] = {k: _f(iso.get(k)) for k in ("A_um", "E_um", "R_um", "B_um", "M_um")}
    new_rows = [{**row, "truth_deviation_x_um": _f(true_dev[k, 0]), "truth_deviation_y_um": _f(true_dev[k, 1])}
                for k, row in enumerate(positions)]
    errors, true_oop = _out_of_plane_errors(obs, truth, rows, ok, out_of_plane)
    out.update(errors)
    if true_oop is not None:
        new_rows = [{**row, "truth_out_of_plane_um": _f(v)} for row, v in zip(new_rows, true_oop)]
    return out, new_rows


def _out_of_plane_errors(obs: Observations, truth: dict[str, Any], rows: np.ndarray, ok: np.ndarray,
                         out_of_plane: tuple[np.ndarray, np.ndarray] | None) -> tuple[dict[str, Any], np.ndarray | None]:
    """The estimate's out-of-plane displacement (``out_of_plane``: value and sigma per capture, um) against truth,
    both off their least-squares plane over ``ok``: the error figures and the true displacement per position (None
    where not compared)."""
    if "board_plane_normal_um" not in truth or out_of_plane is None:
        return {}, None
    est_v, est_s = (np.asarray(v, dtype=float) for v in out_of_plane)
    keep = ok & np.isfinite(est_v) & np.isfinite(est_s)
    if keep.sum() < 4:
        return {}, None
    design = np.column_stack([np.ones(obs.K), obs.target_mm])
    true_v = truth["board_plane_normal_um"][rows]
    true_v = true_v - design @ np.linalg.lstsq(design[keep], true_v[keep], rcond=None)[0]
    err = est_v[keep] - true_v[keep]
    return {"out_of_plane_rms_error_um": _f(np.sqrt(np.mean(err**2))),
            "out_of_plane_z_mean_square": _f(np.mean((err / est_s[keep]) ** 2))}, true_v


def target_truth_comparison(session: Session, section: list[dict[str, Any]]) -> dict[str, Any] | None:
    """results.json ``truth_comparison.targets``: each estimated target pose against the simulator's
    (session.json ``truth.targets``, world = target 0's frame), the rotation error as the left
    perturbation the sigmas are of; None for a real session."""
    from lps_gui.core.geometry.rotation import exp_so3, log_so3

    truth = (session.meta.get("truth") or {}).get("targets")
    if not truth:
        return None
    by_id = {t["id"]: t for t in truth}
    rows, z = [], []
    for r in section:
        t = by_id.get(r["id"])
        if t is None:
            continue
        d_rot = log_so3(exp_so3(np.asarray(r["rvec_rad"], float)) @ exp_so3(np.asarray(t["rvec_rad"], float)).T)
        d_p = np.asarray(r["p_mm"], float) - np.asarray(t["p_mm"], float)
        err = np.r_[d_rot, d_p]
        sigma = np.r_[np.asarray(r["rvec_sigma_rad"], float), np.asarray(r["p_sigma_mm"], float)]
        zs = np.abs(err[sigma > 0]) / sigma[sigma > 0]
        z += zs.tolist()
        rows.append({"id": r["id"], "rvec_error_rad": json_floats(d_rot), "p_error_mm": json_floats(d_p),
                     "max_abs_z": _f(zs.max()) if zs.size else None})
    return {"per_target": rows, "max_abs_z": _f(max(z)) if z else None,
            "z_mean_square": _f(np.mean(np.square(z))) if z else None}
