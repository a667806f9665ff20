"""Corners in mrcal's vnlog format (SPEC 7): ``# filename x y level``.

One row per corner, row-major (SPEC 2 order); a missing corner is ``- - -``
(or level -1); a view whose board was not found is a single ``filename - - -``
row, with the reason in a ``## failed <filename>: <reason>`` comment. Other
``## key = value`` comments carry metadata (e.g. the hash of captures.jsonl).

A session of 1600 views holds 864k rows, so both directions work on numpy
byte arrays, never one Python object per row. Reading first tries
:mod:`lps_gui.io.corners.vnl_fast` (the file as the writer makes it, streamed
in blocks and hashed on the way); any other file, and
every error, goes to the general reader here (tokens found by whitespace
masks, numbers parsed by one bytes-to-float cast, names grouped by runs),
whose messages name the first offending line as a line-by-line reader would.
Comment lines are few and are handled one by one.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lps_gui.errors import InputError
from lps_gui.file_limits import open_regular
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.corners.vnl_fast import comment_fields, read_simple

MAX_CORNERS_BYTES = 2 << 30  # 100000 views (the plan limit) of 54 corners: ~2 GB; the fast reader sizes its table by the file
MAX_GENERAL_BYTES = 32 << 20  # hand-edited files (CR line ends, tabs, odd spaces) go through the general parser,
# which holds ~14 bytes a byte: 256 MB took 3.5 GB; 32 MB (11000 views of 54 corners) stays under 0.5 GB

HEADER = "# filename x y level"

# Bytes str.split() treats as whitespace (ASCII), and those str.splitlines() treats as line breaks.
_WHITESPACE = np.zeros(256, bool)
_WHITESPACE[[9, 10, 11, 12, 13, 28, 29, 30, 31, 32]] = True
_ODD_BREAKS = (b"\r", b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\xc2\x85", b"\xe2\x80\xa8", b"\xe2\x80\xa9")
_ODD_BYTES = np.zeros(256, bool)
_ODD_BYTES[[13, 11, 12, 28, 29, 30, 0xC2, 0xE2]] = True  # first bytes of those breaks: one cheap scan first
_CHUNK = 1 << 18  # tokens parsed per numpy pass: caps the padded temporaries at a few MB
# Unicode spaces inside a line (str.split() splits there too; the line-breaking ones are made \n first), as UTF-8
_UNICODE_SPACES = tuple(chr(c).encode("utf-8") for c in (0xA0, 0x1680, *range(0x2000, 0x200B), 0x202F, 0x205F, 0x3000))


@dataclass
class CornerTable:
    """Detected corners of many views."""

    names: list[str]
    corners_px: np.ndarray  # shape (K, N, 2), NaN where missing
    failed: dict[str, str] = field(default_factory=dict)  # name -> reason
    meta: dict[str, str] = field(default_factory=dict)
    # sha256 of the file's bytes as they were parsed (results.json ``inputs``), None for a table made in memory
    sha256: str | None = field(default=None, compare=False)

    def index(self) -> dict[str, int]:
        return {name: i for i, name in enumerate(self.names)}


# ----------------------------------------------------------------------------- writing


def format_corners_vnl(table: CornerTable) -> str:
    return corners_vnl_bytes(table).decode("utf-8")


def write_corners_vnl(path: Path | str, table: CornerTable) -> None:
    if any(" " in n for n in table.names):
        raise InputError("corners.vnl: file names with spaces cannot be stored; rename the images")
    write_bytes_atomic(path, corners_vnl_bytes(table))


def corners_vnl_bytes(table: CornerTable) -> bytes:
    """The file's bytes: header and comments, then every row built in numpy byte matrices."""
    lines = [HEADER]
    lines += [f"## {key} = {value}" for key, value in table.meta.items()]
    lines += [f"## failed {name}: {reason.replace(chr(10), ' ')}" for name, reason in table.failed.items()]
    head = ("\n".join(lines) + "\n").encode("utf-8")
    if not len(table.names):
        return head
    corners = np.asarray(table.corners_px, float).reshape(len(table.names), -1, 2)
    failed = np.array([n in table.failed for n in table.names]) | ~np.isfinite(corners).any(axis=(1, 2))
    per_view = np.where(failed, 1, corners.shape[1])  # a failed view is one "name - - -" row
    view = np.repeat(np.arange(len(table.names)), per_view)
    xy = np.full((len(view), 2), np.nan)
    ok_rows = ~failed[view]
    xy[ok_rows] = corners[~failed].reshape(-1, 2)
    missing = ~np.isfinite(xy).all(axis=1)
    names = _padded_names(table.names)[view]
    out = [head]
    for lo in range(0, len(view), _CHUNK):
        sl = slice(lo, lo + _CHUNK)
        rows = np.concatenate([names[sl], _number_field(xy[sl, 0], missing[sl]), _number_field(xy[sl, 1], missing[sl]),
                               _level_field(missing[sl])], axis=1)
        out.append(rows[rows != 0].tobytes())  # padding is NUL: dropping it leaves the rows back to back
    return b"".join(out)


def _padded_names(names: list[str]) -> np.ndarray:
    encoded = [n.encode("utf-8") for n in names]
    width = max(len(e) for e in encoded)
    return np.frombuffer(b"".join(e.ljust(width, b"\0") for e in encoded), np.uint8).reshape(len(names), width)


def _number_field(values: np.ndarray, missing: np.ndarray) -> np.ndarray:
    """`` {x:.4f}`` (or `` -``) of every row as a NUL-padded byte matrix, digits identical to Python's."""
    v = np.where(missing, 0.0, values)
    scaled = np.abs(v) * 1e4
    n = np.rint(scaled)
    # x * 1e4 is rounded once; only values within a few ulps of a half are ambiguous: ask Python for those.
    tie = np.abs(scaled - np.floor(scaled) - 0.5) < scaled * 1e-15 + 1e-12
    for i in np.flatnonzero(tie & ~missing):
        n[i] = abs(int(f"{v[i]:.4f}".replace(".", "")))
    n = n.astype(np.int64)
    whole, frac = n // 10000, n % 10000
    n_int = max(1, len(str(int(whole.max(initial=0)))))
    place = 10 ** np.arange(n_int - 1, -1, -1, dtype=np.int64)
    int_digits = (whole[:, None] // place) % 10 + 48
    keep = (np.arange(n_int) >= n_int - _digit_count(whole)[:, None])
    frac_digits = (frac[:, None] // np.array([1000, 100, 10, 1], np.int64)) % 10 + 48
    rows = len(v)
    field = np.zeros((rows, 3 + n_int + 4), np.uint8)
    field[:, 0] = 32
    field[:, 1] = np.where(missing | np.signbit(v), 45, 0)  # '-' for a negative value and for a missing one
    field[:, 2 : 2 + n_int] = np.where(keep, int_digits, 0)
    field[:, 2 + n_int] = 46
    field[:, 3 + n_int :] = frac_digits
    field[missing, 2:] = 0
    return field


def _digit_count(whole: np.ndarray) -> np.ndarray:
    count = np.ones(len(whole), np.int64)
    for p in range(1, 19):
        count += whole >= 10**p
    return count


def _level_field(missing: np.ndarray) -> np.ndarray:
    field = np.empty((len(missing), 3), np.uint8)
    field[:, 0] = 32
    field[:, 1] = np.where(missing, 45, 48)
    field[:, 2] = 10
    return field


# ----------------------------------------------------------------------------- reading


def read_corners_vnl(path: Path | str, n_corners: int) -> CornerTable:
    """Read corners.vnl, checking every view against the board's corner count.

    Raises InputError naming the file and the fix when the file is empty,
    truncated, holds NaNs, or a view has another number of corners (the
    first offending line is named, as a line-by-line reader would).
    """
    path = Path(path)
    stream, st = open_regular(path, "corners file", follow_symlinks=False, missing="corners file not found; run `lps "
                              "detect` first", irregular="not a regular file; delete it and run `lps detect` again")
    with stream:
        if st.st_size > MAX_CORNERS_BYTES:
            raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB, over the {MAX_CORNERS_BYTES / 1e6:.0f} MB limit of a "
                             "corners file; delete it and run `lps detect` again")
        try:
            simple = read_simple(stream, n_corners)
        except OSError:
            simple = None  # the general reader below names the problem
        if simple is not None:
            return CornerTable(simple.names, simple.corners_px, simple.failed, simple.meta, simple.sha256)
        if st.st_size > MAX_GENERAL_BYTES:  # the general parser holds ~10 index arrays per byte
            raise InputError(f"{path}: {st.st_size / 1e6:.0f} MB and not in the form `lps detect` writes (over the "
                             f"{MAX_GENERAL_BYTES / 1e6:.0f} MB this reader takes); delete it and run `lps detect` again")
        stream.seek(0)
        data = stream.read(st.st_size + 1)  # not MAX_GENERAL_BYTES + 1: read(n) allocates n bytes first
    try:
        text = data.decode("utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: corners file not found; run `lps detect` first") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read corners ({exc}); delete it and run `lps detect` again") from exc
    if not text.strip():
        raise InputError(f"{path}: is empty; delete it and run `lps detect` on the session")
    buf = np.frombuffer(data, np.uint8)
    if _ODD_BYTES[buf].any() and any(b in data for b in _ODD_BREAKS):
        # rare: line breaks other than \n, as text mode and splitlines() see them
        buf = np.frombuffer("\n".join(text.splitlines()).encode("utf-8"), np.uint8)
    del text
    spaces = [seq for seq in _UNICODE_SPACES if seq in data] if not data.isascii() else []
    table = _parse(path, buf, n_corners, spaces)
    table.sha256 = hashlib.sha256(data).hexdigest()
    return table


def _parse(path: Path, buf: np.ndarray, n_corners: int, unicode_spaces: list[bytes]) -> CornerTable:
    ws = buf <= 32  # space, \n and the other ASCII whitespace; the rare other control bytes are fixed below
    control = np.flatnonzero((buf < 32) & (buf != 10))
    ws[control] = _WHITESPACE[buf[control]]
    has_nul = bool(len(control)) and bool((buf[control] == 0).any())  # numpy's bytes type would drop a token's NUL
    for seq in unicode_spaces:
        _mark(ws, buf, seq)
    tok_start = np.flatnonzero(~ws & np.concatenate([[True], ws[:-1]]))
    tok_end = np.flatnonzero(~ws & np.concatenate([ws[1:], [True]])) + 1
    del ws
    newline = np.flatnonzero(buf == 10)
    tok_line = np.searchsorted(newline, tok_start)  # 0-based line of every token
    line_first = np.flatnonzero(np.concatenate([[True], tok_line[1:] != tok_line[:-1]]))  # first token of each non-blank line
    line_of = tok_line[line_first]
    n_tok = np.diff(np.concatenate([line_first, [len(tok_start)]]))
    del tok_line
    tok_len = tok_end - tok_start
    size = len(buf)
    buf = np.concatenate([buf, np.zeros(int(tok_len.max(initial=0)) + 2, np.uint8)])  # room for fixed-width windows at the end
    comment = buf[tok_start[line_first]] == ord("#")

    def raw(line: int) -> str:
        lo = newline[line - 1] + 1 if line > 0 else 0
        hi = newline[line] if line < len(newline) else size
        return bytes(buf[lo:hi]).decode("utf-8")

    failed, meta, saw_header = comment_fields([raw(line) for line in line_of[comment]])

    errors: list[tuple[int, int, str]] = []  # (line, rank among errors of one line, message); the first wins
    data_lines, t0, n_data_tok = line_of[~comment], line_first[~comment], n_tok[~comment]
    short = np.flatnonzero(n_data_tok < 3)
    if len(short):
        ln = int(data_lines[short[0]])
        errors.append((ln, 0, f"{path}: line {ln + 1} is truncated ({raw(ln)!r}); delete the file and run `lps detect` again"))
        data_lines, t0, n_data_tok = data_lines[: short[0]], t0[: short[0]], n_data_tok[: short[0]]  # later rows are never looked at

    def is_token(t: np.ndarray, text: bytes) -> np.ndarray:
        hit = tok_len[t] == len(text)
        for i, ch in enumerate(text):
            hit &= buf[tok_start[t] + i] == ch
        return hit

    has_level = n_data_tok > 3
    level_tok = np.where(has_level, t0 + 3, t0)
    missing = is_token(t0 + 1, b"-") | is_token(t0 + 2, b"-") | (has_level & (is_token(level_tok, b"-") | is_token(level_tok, b"-1")))
    numeric = np.flatnonzero(~missing)
    xy = np.full((len(data_lines), 2), np.nan)
    xy_tokens = (t0[numeric, None] + np.array([1, 2])).ravel()
    values = np.empty(len(xy_tokens))
    for lo in range(0, len(xy_tokens), _CHUNK):
        part = xy_tokens[lo : lo + _CHUNK]
        try:
            if has_nul:
                raise ValueError("a NUL byte in the file")
            values[lo : lo + len(part)] = _token_matrix(buf, tok_start[part], tok_len[part]).astype(float)
            continue
        except ValueError:  # find the token, with Python's float() as the judge (numpy's cast is its fast path)
            parsed = [_float_or_none(bytes(buf[tok_start[t] : tok_end[t]]).decode("utf-8")) for t in part]
        bad = next((i for i, v in enumerate(parsed) if v is None), None)
        if bad is None:
            values[lo : lo + len(part)] = parsed
            continue
        bad += lo
        ln = int(data_lines[numeric[bad // 2]])
        errors.append((ln, 1, f"{path}: line {ln + 1} has non-numeric x/y ({raw(ln)!r}); regenerate with `lps detect`"))
        values[lo:bad] = parsed[: bad - lo]
        values = values[: bad - bad % 2]
        break
    finite = np.isfinite(values.reshape(-1, 2)).all(axis=1)
    if not finite.all():
        ln = int(data_lines[numeric[np.argmin(finite)]])
        errors.append((ln, 2, f"{path}: line {ln + 1} holds NaN/inf; write missing corners as '- - -' or re-run `lps detect`"))
    if errors:
        raise InputError(min(errors)[2])
    xy[numeric] = values.reshape(-1, 2)

    if not saw_header:
        raise InputError(f"{path}: missing the '{HEADER}' header; not a corners file, regenerate it with `lps detect`")
    if not len(data_lines):
        raise InputError(f"{path}: holds no corners; run `lps detect` on the session")
    names, view = _group_names(buf, tok_start[t0], tok_len[t0])
    count = np.bincount(view, minlength=len(names))
    corners = np.full((len(names), n_corners, 2), np.nan)
    order = np.argsort(view, kind="stable")  # rows of each view, in file order
    view_first_row = np.concatenate([[0], np.cumsum(count)[:-1]])
    single_missing = (count == 1) & np.isnan(xy[order[view_first_row], 0])
    for i in np.flatnonzero(single_missing):
        failed.setdefault(names[i], "board not found")
    wrong = np.flatnonzero(~single_missing & (count != n_corners))
    if len(wrong):
        i = int(wrong[0])
        raise InputError(
            f"{path}: {names[i]} has {count[i]} corners but the board has {n_corners}; "
            "check inner_corners in board.json or re-run `lps detect`"
        )
    keep = ~single_missing[view[order]]
    rows = order[keep]
    corners[view[rows], (np.arange(len(order)) - view_first_row[view[order]])[keep]] = xy[rows]
    return CornerTable(names, corners, failed, meta)


def _token_matrix(buf: np.ndarray, start: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Tokens as a fixed-width bytes array (NUL-padded, which numpy's bytes dtype ignores).

    ``buf`` must extend at least the longest token past the last token's start.
    """
    width = int(length.max(initial=1))
    mat = np.lib.stride_tricks.sliding_window_view(buf, width)[start]  # copies the rows
    mat[np.arange(width) >= length[:, None]] = 0
    return mat.view(f"S{width}").ravel()


def _mark(ws: np.ndarray, buf: np.ndarray, seq: bytes) -> None:
    """Mark the bytes of every occurrence of ``seq`` (a multi-byte space) as whitespace."""
    n = len(seq)
    hit = buf[: len(buf) - n + 1] == seq[0]
    for i in range(1, n):
        hit &= buf[i : len(buf) - n + 1 + i] == seq[i]
    at = np.flatnonzero(hit)
    for i in range(n):
        ws[at + i] = True


def _float_or_none(token: str) -> float | None:
    try:
        return float(token)
    except ValueError:
        return None


def _group_names(buf: np.ndarray, start: np.ndarray, length: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Distinct names in order of first appearance, and each row's index into them.

    Rows of one view are contiguous in practice, so names are compared run by
    run (a row starts a run when it differs from the row before); only the
    runs' names are decoded and deduplicated.
    """
    run_starts = [0]
    for lo in range(0, len(start), _CHUNK):
        hi = min(lo + _CHUNK + 1, len(start))
        mat = _token_matrix(buf, start[lo:hi], length[lo:hi])
        n = length[lo:hi]  # lengths too: the padding would make "a\0" equal to "a"
        run_starts.extend((lo + 1 + np.flatnonzero((mat[1:] != mat[:-1]) | (n[1:] != n[:-1]))).tolist())
    run_starts_arr = np.array(run_starts)
    run_names = [bytes(buf[s : s + n]).decode("utf-8") for s, n in zip(start[run_starts_arr], length[run_starts_arr])]
    index: dict[str, int] = {}
    run_view = np.array([index.setdefault(n, len(index)) for n in run_names])
    run_len = np.diff(np.concatenate([run_starts_arr, [len(start)]]))
    return list(index), np.repeat(run_view, run_len)
