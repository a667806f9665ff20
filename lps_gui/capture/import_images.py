"""A session from images the user already has (`lps import`, the GUI's File > Import images; SPEC 16).

Everything is checked before the session is created (names, positions,
image sizes from the headers, duplicates), so a bad folder costs a one-line
error and leaves nothing behind. The images are only read: copied into the
session's images/ (the default) or listed where they are (``in_place``: the
session is written into the image folder itself, so every later step reads
only inside the session folder). captures.jsonl lists each with its sha256
as a capture does, ``reported_mm`` equal to ``target_mm`` (no stage reported
it) and ``"source": "import"``.
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lps_gui.camera.folder_replay import IMAGE_EXTENSIONS, natural_key
from lps_gui.capture.import_positions import ImageStop, plan_of, stops_from_csv, stops_from_names, stops_from_step
from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.camera_model import CameraIntrinsics
from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.errors import InputError
from lps_gui.file_limits import check_regular_file, read_file_limited
from lps_gui.io.atomic import sha256_file
from lps_gui.io.image_file import image_size
from lps_gui.io.session import CAPTURES_FILE, CORNERS_FILE, IMAGES_DIR, SESSION_FILE, CaptureRecord, Session
from lps_gui.io.session_paths import resolve_in_session

SOURCE = "import"
MAX_CSV_BYTES = 1 << 26


@dataclass(frozen=True)
class Positions:
    """Where the images were taken: a step (with ``start_mm``, ``directions``, ``runs``), a name pattern or a CSV."""

    step_mm: float | None = None
    start_mm: float = 0.0
    directions: str = "+"
    runs: int = 1
    names: str | None = None
    csv: Path | None = None

    def __post_init__(self) -> None:
        given = [n for n, v in (("--step", self.step_mm), ("--from-names", self.names), ("--positions", self.csv))
                 if v is not None]
        if len(given) != 1:
            raise InputError("give the positions one way: --step MM (with --start), --from-names PATTERN or "
                             f"--positions FILE.csv{f', not {given[0]} and {given[1]}' if len(given) > 1 else ''}")
        if self.step_mm is None and (self.directions != "+" or self.runs != 1):
            raise InputError("--directions and --runs go with --step; names or a CSV give them per image")

    def to_dict(self) -> dict[str, Any]:
        """session.json's record of how the positions were given."""
        if self.step_mm is not None:
            return {"step_mm": self.step_mm, "start_mm": self.start_mm, "directions": self.directions, "runs": self.runs}
        return {"from_names": self.names} if self.names is not None else {"positions_csv": Path(self.csv).name}


@dataclass(frozen=True)
class ImportedImage:
    """An image checked for import: where it is, where it was taken, its size and hash."""

    path: Path
    stop: ImageStop
    size: tuple[int, int]
    sha256: str
    mtime: float


def import_images(
    images_dir: Path | str,
    out: Path | str | None,
    board: Board,
    positions: Positions,
    intrinsics: CameraIntrinsics | None = None,
    in_place: bool = False,
    extra: dict[str, Any] | None = None,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> Path:
    """Write a session from the images of ``images_dir``; returns the session folder."""
    images_dir = Path(images_dir)
    if not images_dir.is_dir():
        raise InputError(f"{images_dir}: image folder not found; check the path")
    folder = session_folder(images_dir, out, in_place)
    check_free(folder, in_place)
    stops = stops_of(images_dir, positions)
    plan = plan_of(stops)
    images = checked_images(images_dir, stops, intrinsics, in_place, progress, cancel)
    made_images_dir = not (folder / IMAGES_DIR).exists()
    width, height = images[0].size
    session = Session.create(
        folder, board, plan, intrinsics,
        camera={"driver": SOURCE, "width": width, "height": height},
        stage={"driver": SOURCE},
        extra={**(extra or {}), "import": {"positions": positions.to_dict(), "images": "in place" if in_place else "copied",
                                           "from": str(images_dir.resolve())}},
    )
    if in_place and made_images_dir:
        _remove_if_empty(folder / IMAGES_DIR)  # Session.create's folder for captured images: none here
    write_records(session, images, in_place, progress, cancel)
    return folder


def session_folder(images_dir: Path, out: Path | str | None, in_place: bool) -> Path:
    """The session folder: ``out``, or with ``in_place`` the image folder itself."""
    if not in_place:
        if out is None:
            raise InputError("give --out SESSION (a new folder), or --in-place to write the session beside the images")
        return Path(out)
    if out is not None and Path(out).resolve() != images_dir.resolve():
        raise InputError(f"--in-place writes the session into {images_dir} itself; drop --out {out}")
    return images_dir


def check_free(folder: Path, in_place: bool) -> None:
    """Refuse a folder holding a session (or, when copying, anything at all): nothing there is overwritten."""
    for name in (SESSION_FILE, CAPTURES_FILE, CORNERS_FILE):
        if (folder / name).exists() or (folder / name).is_symlink():
            raise InputError(f"{folder}: already holds a session ({name}); choose a new folder for the import")
    if not in_place and folder.is_dir() and any(folder.iterdir()):
        raise InputError(f"{folder}: is not empty; give a new or an empty folder for the session")
    if not in_place and folder.exists() and not folder.is_dir():
        raise InputError(f"{folder}: exists and is not a folder; give a new folder for the session")


def folder_images(images_dir: Path) -> list[str]:
    """The image files of ``images_dir`` (not its sub-folders or hidden files) in natural name order.

    A file that is not an image by its extension is an error naming it: a
    stray file would otherwise shift every position after it.
    """
    with os.scandir(images_dir) as entries:
        names = [e.name for e in entries if not e.name.startswith(".") and not e.is_dir()]
    for name in names:
        check_image_name(images_dir / name)
    if not names:
        raise InputError(f"{images_dir}: no images ({', '.join(IMAGE_EXTENSIONS)}); check the folder")
    return sorted(names, key=natural_key)


def check_image_name(path: Path, where: str = "") -> None:
    """InputError unless ``path`` has an image file's extension."""
    if path.suffix.lower() not in IMAGE_EXTENSIONS:
        raise InputError(f"{where}{path}: not an image file ({', '.join(IMAGE_EXTENSIONS)}); move it out of the folder")


def stops_of(images_dir: Path, positions: Positions) -> list[ImageStop]:
    """Every image to import with its position, in capture order."""
    if positions.csv is None:
        files = folder_images(images_dir)
        if positions.names is not None:
            return stops_from_names(files, positions.names, f"{images_dir}/")
        return stops_from_step(files, positions.start_mm, positions.step_mm, positions.directions, positions.runs)
    path = Path(positions.csv)
    try:
        text = read_file_limited(path, MAX_CSV_BYTES, "positions file").decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file; give a CSV of file,target[,direction,run]") from None
    stops, lines = stops_from_csv(text, str(path))
    for stop, n in zip(stops, lines):
        where = f"{path}: line {n}: "
        full = resolve_in_session(images_dir, stop.file, where.rstrip(": "))  # inside the image folder
        if not full.exists():
            raise InputError(f"{where}{stop.file} not found in {images_dir}; fix the row or add the image")
        check_image_name(full, where)
    return stops


def checked_images(images_dir: Path, stops: list[ImageStop], intrinsics: CameraIntrinsics | None, in_place: bool,
                   progress: ProgressFn, cancel: CancelToken | None) -> list[ImportedImage]:
    """Size (from the header) and hash of every image; one size, the intrinsics' size, no image twice."""
    out: list[ImportedImage] = []
    by_hash: dict[str, str] = {}
    for i, stop in enumerate(stops):
        if cancel is not None:
            cancel.check("import")
        path = images_dir / stop.file
        st = check_regular_file(path, "image", follow_symlinks=not in_place)
        size = image_size(path)
        first = out[0] if out else None
        if first is not None and size != first.size:
            raise InputError(f"{path}: {size[0]}x{size[1]} px, but {first.path.name} is {first.size[0]}x{first.size[1]}; "
                             "a session's images come from one camera at one size: move the odd ones out")
        if intrinsics is not None and tuple(intrinsics.image_size) != tuple(size):
            w, h = intrinsics.image_size
            raise InputError(f"{path}: {size[0]}x{size[1]} px, but the intrinsics are for {w}x{h}; give the "
                             "intrinsics of this camera at this resolution")
        sha = sha256_file(path)
        if sha in by_hash:
            raise InputError(f"{path}: the same image as {by_hash[sha]} (equal sha256); remove the copy")
        by_hash[sha] = stop.file
        out.append(ImportedImage(path, stop, size, sha, st.st_mtime))
        progress(i + 1, len(stops) * (1 if in_place else 2), f"checked {stop.file}")
    return out


def write_records(session: Session, images: list[ImportedImage], in_place: bool, progress: ProgressFn,
                  cancel: CancelToken | None) -> None:
    """List every image in captures.jsonl (copied first unless ``in_place``), in capture order."""
    frames: dict[tuple[int, str, float], int] = {}
    n = len(images)
    for index, image in enumerate(images):
        if cancel is not None:
            cancel.check("import")
        stop = image.stop
        if in_place:
            rel = stop.file
        else:
            data = read_file_limited(image.path)
            if hashlib.sha256(data).hexdigest() != image.sha256:
                raise InputError(f"{image.path}: changed while being imported; import again into a new folder")
            rel, _ = session.write_image(stop.file, data)
        key = (stop.run, stop.direction, stop.target_mm)
        frames[key] = frames.get(key, -1) + 1
        session.append(CaptureRecord(index=index, run=stop.run, direction=stop.direction, target_mm=stop.target_mm,
                                     reported_mm=stop.target_mm, file=rel, sha256=image.sha256, time=image.mtime,
                                     frame=frames[key], source=SOURCE))
        progress(index + 1 + (0 if in_place else n), n if in_place else 2 * n, f"listed {rel}")


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:  # not empty: leave it
        pass
