"""Are the corners usable and the results still those of the session's current files?

corners.vnl names the image hash of every view (:mod:`lps_gui.io.corners.hashes`)
and results.json the sha256 of session.json, captures.jsonl and corners.vnl
it was computed from. Estimation refuses corners of replaced images; the
report says when results.json no longer matches the session. A view whose
corners lie on one line fixes no pose and is refused by name.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

from lps_gui.errors import InputError
from lps_gui.io.atomic import sha256_file
from lps_gui.io.corners.hashes import image_hashes, stale_views
from lps_gui.io.corners.vnl import CornerTable
from lps_gui.io.results.model import Results, as_results
from lps_gui.io.results.sections import Parameters
from lps_gui.io.session import SESSION_FILE
from lps_gui.pipeline.session_input import SessionInput


def corners_of_records(session: SessionInput, table: Any, records: Sequence[Any], views_whole: bool = True) -> Any:
    """The corners (K, N, 2) of every capture in captures.jsonl order, checked (stale images, views missing,
    collinear views); ``table`` a corners.vnl of one board or of targets (names, meta, corners_px).

    ``views_whole`` False (targets): only the corner values are checked here, the caller judges the
    geometry of each target in a view.
    """
    import numpy as np

    check_corners_current(session, table, records)
    rows = table.index() if hasattr(table, "index") else {name: i for i, name in enumerate(table.names)}
    missing = [r.file for r in records if r.file not in rows]
    if missing:
        raise InputError(f"{session.corners_path}: {len(missing)} captured image(s) have no corners (first: "
                         f"{missing[0]}); run `lps detect {session.folder}`")
    order = np.array([rows[r.file] for r in records])
    # captures.jsonl and corners.vnl list the views in one order when detection wrote the file: no copy then
    in_order = len(order) == len(table.names) and bool((order == np.arange(len(order))).all())
    corners = table.corners_px if in_order else table.corners_px[order]
    if views_whole:
        check_view_geometry(corners, [r.file for r in records], session.corners_path)
    else:
        check_corner_values(corners, [r.file for r in records], session.corners_path)
    return corners


def check_corners_current(session: SessionInput, table: CornerTable, records: Sequence[Any]) -> None:
    """InputError when corners.vnl holds corners of images that were replaced since detection."""
    stale = stale_views(table, image_hashes(records))
    if stale:
        raise InputError(f"{session.corners_path}: {len(stale)} view(s) were detected in an older image "
                         f"(first: {stale[0]}; captures.jsonl lists a new sha256); run `lps detect {session.folder}`")


MAX_CORNER_PX = 1e6  # no camera is a million pixels across


def check_view_geometry(corners_px: Any, names: Sequence[str], source: Path | str) -> None:
    """InputError naming the views whose corners lie on one line (they would give a silent wrong position)
    or that hold a corner no camera can see (1e308 overflows the solver's sums)."""
    import numpy as np

    from lps_gui.core.geometry.view_geometry import collinear_views

    check_corner_values(corners_px, names, source)
    bad = collinear_views(corners_px)
    if bad:
        seen = np.all(np.isfinite(np.asarray(corners_px, float)[bad]), axis=-1).sum(axis=1)
        n = np.asarray(corners_px).shape[1]
        if np.all(seen < n):  # part of the board is missing in each: it is leaving the image
            raise InputError(f"{source}: the board leaves the camera's view in {len(bad)} view(s) (first: "
                             f"{names[bad[0]]}, {int(seen[0])} of {n} corners seen, all on one line); move the "
                             "camera back or shorten the travel (`lps plan-rig` checks a plan before capture)")
        raise InputError(f"{source}: {len(bad)} view(s) have all corners on one line (first: {names[bad[0]]}); "
                         "the board is edge-on or the corners are corrupt: re-run `lps detect` or remove the view")


def check_corner_values(corners_px: Any, names: Sequence[str], source: Path | str) -> None:
    """InputError naming a view with a corner no camera can see (1e308 overflows the solver's sums)."""
    import numpy as np

    xy = np.asarray(corners_px, float)
    absurd = ~(np.isnan(xy) | (np.abs(xy) <= MAX_CORNER_PX))
    if absurd.any():
        view = int(np.argwhere(absurd)[0][0])
        raise InputError(f"{source}: view {names[view]} has a corner at {xy[absurd][0]:g} px (over {MAX_CORNER_PX:g}); "
                         "the corners are corrupt: delete corners.vnl and run `lps detect` again")


def session_inputs(session: SessionInput, intrinsics_source: str, known: dict[str, str | None] | None = None
                   ) -> dict[str, Any]:
    """results.json ``inputs``: where the data came from, with the sha256 of each input file.

    ``known``: hashes already taken of the bytes that were read (corners.vnl is hashed as it is parsed), not
    read again.
    """
    inputs: dict[str, Any] = {"session": str(session.folder), "intrinsics_source": intrinsics_source, "sha256": {}}
    for name in (SESSION_FILE, session.captures_path.name, session.corners_path.name):
        path = session.folder / name
        if (known or {}).get(name):
            inputs["sha256"][name] = known[name]
        elif path.exists():
            inputs["sha256"][name] = sha256_file(path)
    return inputs


def stale_inputs(session_dir: Path | str, results: Results | dict[str, Any]) -> list[str]:
    """Session files whose sha256 differs from the one results.json was computed from."""
    folder = Path(session_dir)
    inputs = as_results(results).inputs
    recorded = inputs.sha256 if inputs else {}
    changed = []
    for name, digest in recorded.items():
        path = folder / str(name)
        if "/" in str(name) or not path.is_file():
            continue
        if sha256_file(path) != digest:
            changed.append(str(name))
    return changed


def require_current_results(session_dir: Path | str, results: Results, command: str) -> None:
    """InputError when results.json was not computed from this session's current files.

    The check `lps report` makes (exit 3 after writing), made before anything is written by the commands whose
    output drives a machine or other software (compensate, export, compare): a results.json copied from another
    session, or one older than the session's corners, would give a confident table of another stage.
    """
    folder = Path(session_dir)
    if results.inputs is None or not results.inputs.sha256:
        raise InputError(f"{folder}/results.json: records no input hashes (made by another program or an old lps); "
                         f"run `lps estimate {folder}` before `lps {command}`")
    changed = stale_inputs(folder, results)
    if changed:
        raise InputError(f"{folder}/results.json: was computed from other files ({', '.join(changed)} differ: results of "
                         f"another session, or of this one before it changed); run `lps estimate {folder}` before "
                         f"`lps {command}`")


MAX_PLAUSIBLE_NOISE_PX = 5.0  # sub-pixel corners scatter ~0.1 px; 5 px means the model or the corners are wrong


def result_doubts(p: Parameters) -> list[str]:
    """Why a finished estimate (its fit: results ``parameters``) must not be trusted (empty when nothing is wrong)."""
    doubts = []
    if p.converged is False:
        iterations = "?" if p.iterations is None else p.iterations
        doubts.append(f"the solver did not converge in {iterations} iterations; the positions are not "
                      "a solution: check the corners (`lps detect --force`) and the intrinsics")
    sigma = p.sigma_px
    if sigma is None or not sigma == sigma or sigma > MAX_PLAUSIBLE_NOISE_PX:
        doubts.append(f"corner noise {sigma if sigma is not None else 'unknown'} px is implausible (over "
                      f"{MAX_PLAUSIBLE_NOISE_PX:g} px); the corners or the intrinsics do not fit the images")
    return doubts
