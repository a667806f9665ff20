"""`lps export`: every capture's measured camera pose for COLMAP, nerfstudio or a CSV (SPEC 12).

Poses come from results.json: the common rotation and line of the estimate,
each capture's measured position along it, and the measured straightness
when results.json marks it resolved (otherwise the fitted line is the best
knowledge and per-view straightness would only add noise; ``on`` forces it).
Outlier and unusable views are left out and listed in ``excluded.txt``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lps_gui.core.models.export_poses import camera_centres, world_to_camera
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_text_atomic
from lps_gui.io.export_files import write_colmap, write_nerfstudio, write_poses_csv
from lps_gui.io.intrinsics_file import intrinsics_from_dict
from lps_gui.io.results.keys import MEASURED_MM
from lps_gui.io.results.sections import Figures
from lps_gui.io.session import Session
from lps_gui.pipeline.compensate import session_results

FORMATS = ("colmap", "nerfstudio", "csv")


@dataclass
class ExportResult:
    files: list[Path] = field(default_factory=list)
    n_exported: int = 0
    excluded: list[str] = field(default_factory=list)
    straightness_used: bool = False


def straightness_resolved(figures: Figures) -> tuple[bool, bool]:
    """Which straightness components (v1, v2) results.json calls resolved (``figures.straightness.v1/v2``).

    A span of per-view values is no test: the span of K noisy values is
    several sigmas by itself, and adding per-view noise to the line moves
    every camera off its best pose. Only a component whose profile the data
    resolve (core.resolution: above what noise alone would span) moves the
    exported cameras off the fitted line.
    """
    st = figures.straightness
    if st is None:
        return (False, False)
    return tuple(bool(v is not None and v.resolved) for v in (st.v1, st.v2))  # type: ignore[return-value]


def export_session(session_dir: Path | str, fmt: str, out: Path | str, straightness: str = "auto") -> ExportResult:
    """Write ``fmt`` files for ``session_dir`` into ``out``; ``straightness``: auto | on | off."""
    if fmt not in FORMATS:
        raise InputError(f"--format {fmt}: choose one of {', '.join(FORMATS)}")
    session = Session.open(session_dir)
    results = session_results(session.folder, "export")
    if results.planar:
        raise InputError(f"{session.folder}: a planar (X,Y) session; lps export writes the poses of a line (1-D "
                         "sessions) only, so there is nothing to re-estimate: use results.json's positions instead")
    p = results.parameters.raw
    try:
        R = np.asarray(p["R_cam_board"], dtype=float)
        l0, n = np.asarray(p["l0_cam_mm"], dtype=float), np.asarray(p["n_cam"], dtype=float)
    except KeyError as exc:
        raise InputError(f"{session.folder}/results.json: no {exc} in parameters; estimate the session again") from exc
    if results.intrinsics is None:
        raise InputError(f"{session.folder}/results.json: no intrinsics; estimate the session again")
    intr = intrinsics_from_dict(results.intrinsics.raw, "results.json")
    rows = [r.raw for r in results.positions]
    ref = [r for r in rows if r.get("index") == results.parameters.reference_index]
    if not ref:
        raise InputError(f"{session.folder}/results.json: the reference capture is missing; estimate the session again")
    t_ref = float(ref[0]["target_mm"])
    keep = [r for r in rows if r.get("used", True) and not r.get("outlier") and r.get(MEASURED_MM) is not None]
    res = ExportResult(excluded=[f"{r.get('file')}  {r.get('outlier_reason') or 'not used'}" for r in rows if r not in keep])
    if not keep:
        raise InputError(f"{session.folder}: no usable capture to export")
    s = np.array([float(r[MEASURED_MM]) - t_ref for r in keep])
    use = (True, True) if straightness == "on" else straightness_resolved(results.figures) if straightness == "auto" else (False, False)
    st = None
    if any(use):
        st = 1e-3 * np.array([[float(r.get(f"straightness_um_{k}") or 0.0) if use[k - 1] else 0.0 for k in (1, 2)]
                              for r in keep])
    res.straightness_used = st is not None
    C = camera_centres(R, l0, n, s, st)
    names = [str(r["file"]) for r in keep]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if fmt == "colmap":
        res.files = write_colmap(out, intr, R, world_to_camera(R, C), names, session.board().object_points())
    elif fmt == "nerfstudio":
        root = os.path.relpath(session.folder.resolve(), out.resolve())
        res.files = [write_nerfstudio(out, intr, R, C, names, Path(root).as_posix())]
    else:
        nominal = camera_centres(R, l0, n, np.array([float(r["target_mm"]) - t_ref for r in keep]))
        table = [{**{k: r.get(k) for k in ("index", "run", "direction", "file", "target_mm", MEASURED_MM)},
                  **dict(zip(("nominal_x_mm", "nominal_y_mm", "nominal_z_mm"), map(float, cn))),
                  **dict(zip(("measured_x_mm", "measured_y_mm", "measured_z_mm"), map(float, cm)))}
                 for r, cn, cm in zip(keep, nominal, C)]
        res.files = [write_poses_csv(out / "camera_centres.csv", table)]
    path = out / "excluded.txt"
    write_text_atomic(path, "".join(f"{line}\n" for line in res.excluded))
    res.files.append(path)
    res.n_exported = len(keep)
    return res
