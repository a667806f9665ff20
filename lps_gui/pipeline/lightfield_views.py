"""Every view of a scene session with what the measurement says of it: position, sigma, rotation, centre.

A scene view is matched to the measured stops of the same approach direction; its position is the
measurement's position curve at the view's *commanded* position (the target, or what a compensation
table sent instead), interpolated between measured stops on a line, the stop itself on a plane. Runs of
one stop are averaged; their scatter (the stage's repeatability: the scene visits the stop once more)
adds to the measurement's sigma. The rotation of a view is what the measurement resolves per view: the
error motions of SPEC 14 when targets at two depths gave them (every stop's full pose); with one board,
the image rotation and the board-plane shift across the motion taken as a tilt
(:func:`lps_gui.core.models.lightfield_views.tilt_from_board_shift`), both resolved per view to a few
urad, where one board's per-view 6-DOF tilts scatter by ~100 urad (SPEC 11) even when their profile is
resolved. A planar measurement has no per-view rotation (the common orientation only).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.models.lightfield_views import tilt_from_board_shift
from lps_gui.core.models.lps_model import unit
from lps_gui.errors import InputError
from lps_gui.io.intrinsics_file import intrinsics_from_dict
from lps_gui.io.results.keys import MEASURED_MM
from lps_gui.io.results.model import Results
from lps_gui.io.session import Session
from lps_gui.pipeline.results.error_motions import BASIS_TARGETS


@dataclass(frozen=True)
class MeasuredGeometry:
    """The measurement's common orientation, motion axes (3, D), origin and intrinsics."""

    R: np.ndarray
    axes: np.ndarray  # (3, D) unit motion directions in the board frame
    origin: np.ndarray  # (3,) camera centre at the reference capture's position, board frame
    ref_mm: np.ndarray  # (D,) the reference capture's target: positions are relative to it in the model
    intrinsics: CameraIntrinsics
    board_depth_mm: float  # distance of the board's centre along the optical axis


@dataclass(frozen=True)
class SceneViews:
    """The scene session's views (capture order) and what the measurement says of each."""

    index: np.ndarray  # (K,)
    files: list[str]
    nominal_mm: np.ndarray  # (K, D)
    commanded_mm: np.ndarray  # (K, D)
    position_mm: np.ndarray  # (K, D) measured
    sigma_um: np.ndarray  # (K, D)
    tilt_rad: np.ndarray  # (K, 3) world frame
    image_rotation_rad: np.ndarray  # (K,) about the optical axis
    rotation_source: str

    @property
    def D(self) -> int:
        return self.position_mm.shape[1]

    def centres(self, g: MeasuredGeometry) -> np.ndarray:
        """Camera centres (K, 3) mm on the measured line or plane (no straightness: SPEC 17, no translation change)."""
        return g.origin + (self.position_mm - g.ref_mm) @ g.axes.T


def targets_basis(results: Results) -> bool:
    """Whether results.json's error motions come from every stop's full pose against targets at two depths."""
    em = results.error_motions
    return em is not None and em.basis == BASIS_TARGETS and len(em.frame_world) == 3


def measured_geometry(results: Results, session: Session) -> MeasuredGeometry:
    """The common orientation and motion of the measurement; with SPEC 14's full poses, the motion axis of the
    camera centres (error_motions.frame_world), which a linear roll does not bend as it bends the line of a
    constant-orientation fit (a roll gradient b looks like a line turned by b Z at the board)."""
    p = results.parameters.raw
    where = f"{session.folder}/results.json"
    if results.intrinsics is None:
        raise InputError(f"{where}: no intrinsics; estimate the measurement again")
    try:
        R = np.asarray(p["R_cam_board"], dtype=float)
        l0 = np.asarray(p["l0_cam_mm"], dtype=float)
        if results.planar:
            axes = np.stack([unit(np.asarray(p["u_x_board"], float)), unit(np.asarray(p["u_y_board"], float))], axis=1)
        else:
            axes = unit(-R.T @ np.asarray(p["n_cam"], dtype=float))[:, None]
            if targets_basis(results):
                axes = unit(np.asarray(results.error_motions.frame_world, dtype=float)[:, 0])[:, None]
    except KeyError as exc:
        raise InputError(f"{where}: no {exc} in parameters; estimate the measurement again") from None
    ref = [r.raw for r in results.positions if r.raw.get("index") == results.parameters.reference_index]
    if not ref:
        raise InputError(f"{where}: the reference capture is missing; estimate the measurement again")
    ref_mm = np.array([ref[0]["target_x_mm"], ref[0]["target_y_mm"]] if results.planar else [ref[0]["target_mm"]], float)
    X0 = session.board().centre_mm() if session.targets() is None else np.zeros(3)
    return MeasuredGeometry(R, axes, -R.T @ l0, ref_mm, intrinsics_from_dict(results.intrinsics.raw, where),
                            float((R @ X0 + l0)[2]))


def _num(v: Any) -> float:
    return float("nan") if v is None else float(v)


def _measured_table(results: Results, g: MeasuredGeometry) -> dict[str, np.ndarray]:
    """Per usable measured capture: direction, target (K, D), position (K, D), sigma (K, D), tilt (K, 3), phi (K,)."""
    rows = [r.raw for r in results.positions
            if r.raw.get("used", True) and not r.raw.get("outlier")
            and (r.raw.get("measured_x_mm") if results.planar else r.raw.get(MEASURED_MM)) is not None]
    if not rows:
        raise InputError("the measurement has no usable capture; estimate it again")
    keys = (("target_x_mm", "target_y_mm"), ("measured_x_mm", "measured_y_mm"), ("sigma_x_um", "sigma_y_um")) \
        if results.planar else (("target_mm",), (MEASURED_MM,), ("sigma_um",))
    target, pos, sig = (np.array([[_num(r.get(k)) for k in ks] for r in rows]) for ks in keys)
    tilt, phi, source = np.zeros((len(rows), 3)), np.zeros(len(rows)), "none (a planar measurement: common orientation)"
    if not results.planar:
        R, u = g.R, g.axes[:, 0]
        motions = np.array([[_num(r.get(k)) for k in ("eax_urad", "ebx_urad", "ecx_urad")] for r in rows])
        if targets_basis(results) and np.isfinite(motions).any():
            # SPEC 14: targets at two depths resolve the angles per stop (relative to their mean) in the stage frame
            F = np.asarray(results.error_motions.frame_world, dtype=float)
            seen = np.isfinite(motions)
            mean = np.nansum(motions, axis=0) / np.maximum(seen.sum(axis=0), 1)
            m = np.where(seen, motions - mean, 0.0)
            tilt = 1e-6 * m @ F.T
            source = "error motions (SPEC 14): " + ", ".join(
                n for n, ok in zip(("EAX", "EBX", "ECX"), np.isfinite(motions).any(axis=0)) if ok)
        else:
            shift = np.array([_num(r.get("straightness_um_1")) for r in rows])
            rot = np.array([_num(r.get("image_rotation_urad")) for r in rows])
            tilt = tilt_from_board_shift(R, u, g.board_depth_mm, 1e-3 * np.nan_to_num(shift))
            phi = -1e-6 * np.nan_to_num(rot)
            source = "image rotation and the board-plane shift across the motion taken as a tilt (one board, SPEC 11)"
    return {"direction": np.array([str(r.get("direction", "+")) for r in rows]), "target": target, "position": pos,
            "sigma": sig, "tilt": tilt, "phi": phi, "source": np.array([source])}


def _stops(table: dict[str, np.ndarray], direction: str) -> dict[str, np.ndarray]:
    """The measured stops of one direction, runs averaged; sigma^2 = mean sigma^2 / n + run scatter^2 (1 + 1/n)."""
    sel = table["direction"] == direction
    if not sel.any():
        return {}
    keys, inverse = np.unique(np.round(table["target"][sel], 9), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    n = np.bincount(inverse).astype(float)
    out: dict[str, np.ndarray] = {"target": keys}
    for name in ("position", "tilt", "phi"):
        v = table[name][sel]
        out[name] = np.stack([v[inverse == k].mean(axis=0) for k in range(len(keys))])
    pos, sig = table["position"][sel], table["sigma"][sel]
    var = np.stack([(sig[inverse == k] ** 2).mean(axis=0) / n[k]
                    + (np.var(1e3 * pos[inverse == k], axis=0, ddof=1) * (1 + 1 / n[k]) if n[k] > 1 else 0.0)
                    for k in range(len(keys))])
    out["sigma"] = np.sqrt(var)
    return out


def scene_views(scene: Session, results: Results, g: MeasuredGeometry) -> SceneViews:
    """The scene's captures matched to the measurement (one-line error for a view it cannot place)."""
    records = scene.records()
    if not records:
        raise InputError(f"{scene.folder}: no captures listed; capture the scene first")
    if bool(scene.planar) != bool(results.planar):
        raise InputError(f"{scene.folder}: a {'planar' if scene.planar else 'one-axis'} scene cannot use a "
                         f"{'planar' if results.planar else 'one-axis'} measurement")
    table = _measured_table(results, g)
    D = g.axes.shape[1]
    nominal = np.array([np.atleast_1d(np.asarray(r.target_mm, float)) for r in records]).reshape(-1, D)
    commanded = np.array([np.atleast_1d(np.asarray(r.commanded_mm if r.commanded_mm is not None else r.target_mm,
                                                   float)) for r in records]).reshape(-1, D)
    K = len(records)
    pos, sig, tilt, phi = np.zeros((K, D)), np.zeros((K, D)), np.zeros((K, 3)), np.zeros(K)
    for direction in sorted({r.direction for r in records}):
        stops = _stops(table, direction)
        mine = np.flatnonzero([r.direction == direction for r in records])
        if not stops:
            raise InputError(f"{scene.folder}: the measurement has no stop approached '{direction}'; capture the scene "
                             "with the measurement's directions")
        if D == 1:
            x = stops["target"][:, 0]
            step = float(np.median(np.diff(x))) if x.size > 1 else 0.0
            c = commanded[mine, 0]
            off = (c < x[0] - 0.5 * step - 1e-9) | (c > x[-1] + 0.5 * step + 1e-9)
            if off.any():
                k = mine[int(np.flatnonzero(off)[0])]
                raise InputError(f"{scene.folder}: view {records[k].index} at {c[off][0]:g} mm is outside the measured "
                                 f"travel {x[0]:g}..{x[-1]:g} mm; measure the stage there first")
            interp = lambda v: np.interp(c, x, v)  # noqa: E731
            pos[mine, 0] = interp(stops["position"][:, 0])  # the measured curve between its stops
            sig[mine, 0] = interp(stops["sigma"][:, 0])
            tilt[mine] = np.stack([interp(stops["tilt"][:, j]) for j in range(3)], axis=1)
            phi[mine] = interp(stops["phi"])
        else:
            for k in mine:
                hit = np.flatnonzero(np.all(np.abs(stops["target"] - nominal[k]) < 1e-6, axis=1))
                if hit.size == 0:
                    raise InputError(f"{scene.folder}: view {records[k].index} at {tuple(nominal[k])} mm is not a "
                                     "usable measured stop (missing or an outlier there); re-measure that stop or "
                                     "leave the view out")
                pos[k], sig[k] = stops["position"][hit[0]], stops["sigma"][hit[0]]
    return SceneViews(np.array([r.index for r in records]), [r.file for r in records], nominal, commanded, pos, sig,
                      tilt, phi, str(table["source"][0]))
