"""The common corners.vnl, read as it streams in: the well-formed file and nothing else.

``lps detect`` (and mrcal's tools) write one ``name x y level`` row per
corner: single spaces, ``\\n`` line ends, fixed-point numbers, the comments
above the rows, each view's rows together. Such a file is read in blocks of
whole lines into one reused buffer (memory: the corners, not the file) and
hashed on the way. A block needs no per-token search: its separators must
come in groups of (space, space, space, newline), one group per row. x and
y are read digit column by digit column into an exact integer mantissa and
divided once by a power of ten; both are exact in a double, so the quotient
is the correctly rounded value, the one Python's ``float()`` gives.

Anything else (non-ASCII, tabs, CR, blank lines, comments between rows,
three or five fields, exponents, NaN, interleaved views, a view with another
corner count, any error) returns None and the caller's general reader reads
the file again: it keeps the one wording of every error, and this path is
an optimisation only, which must give the general reader's table whenever it
gives one (``tests/io/test_corners_vnl_fast.py`` runs both on every case).
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from typing import BinaryIO

import numpy as np

_BLOCK = 1 << 20  # bytes per read: the block's temporaries stay in cache, and the numpy calls per block are few
_MAX_WIDTH = 16  # sign, point and 14 digits: every mantissa is an exact integer below 2**53
_SPACE, _NEWLINE, _HASH, _MINUS, _POINT, _ZERO, _ONE = 32, 10, 35, 45, 46, 48, 49
_ROW_SEPARATORS = int(np.frombuffer(bytes([_SPACE, _SPACE, _SPACE, _NEWLINE]), np.uint32)[0])


@dataclass
class Simple:
    """What a well-formed corners.vnl holds, and the sha256 of its bytes."""

    names: list[str]
    corners_px: np.ndarray  # shape (K, N, 2), NaN where missing
    failed: dict[str, str]
    meta: dict[str, str]
    sha256: str


@dataclass
class _Rows:
    """The rows read so far: (x, y) of each (NaN when missing), and where each view's run begins."""

    file_bytes: int
    xy: np.ndarray = field(default_factory=lambda: np.empty((0, 2)))  # shape (capacity, 2)
    count: int = 0
    run_first: list[np.ndarray] = field(default_factory=list)  # global row index of each run's first row
    run_missing: list[np.ndarray] = field(default_factory=list)  # is that row a missing corner
    run_names: list[str] = field(default_factory=list)
    last_name: bytes = b""


def read_simple(stream: BinaryIO, n_corners: int) -> Simple | None:
    """The table of a well-formed corners.vnl read from ``stream``, or None (read it with the general reader).

    ``failed`` and ``meta`` come from the ``##`` comments, read as the
    general reader reads them; a view written as one ``name - - -`` row gets
    "board not found" unless a comment gives its reason.
    """
    size = os.fstat(stream.fileno()).st_size
    rows = _Rows(size)
    margin = _MAX_WIDTH  # room before the first row for the windows of right-aligned numbers
    buf = bytearray(margin + _BLOCK)
    view = memoryview(buf)
    comments: list[str] | None = []  # None once the rows began
    header = None
    carry = 0  # bytes of an unfinished line kept at the buffer's start (after the margin)
    digest = hashlib.sha256()  # of the bytes parsed, for results.json (in cache here: no second read of the file)
    while True:
        got = stream.readinto(view[margin + carry :])
        digest.update(view[margin + carry : margin + carry + got])
        end = margin + carry + got
        last = buf.rfind(b"\n", margin, end) + 1 if got else end  # at the end of the file the last line needs no newline
        if got and last == 0:  # no line ends yet
            if end == len(buf):  # a line longer than the buffer: not a corners row
                return None
            carry = end - margin
            continue
        pos = margin
        if comments is not None:
            pos = _comment_lines(buf, margin, last, comments)
            if pos is None:
                return None
            if pos < last or not got:  # the rows begin (or there are none)
                header = _read_comments(comments)
                if header is None:
                    return None
                comments = None
        if pos < last and not _read_rows(np.frombuffer(buf, np.uint8, last), pos, rows, final=not got,
                                         has_dash=buf.find(b"-", pos, last) >= 0):
            return None
        if not got:
            break
        carry = end - last
        buf[margin : margin + carry] = buf[last:end]
    sha256 = digest.hexdigest() if header is not None and rows.count else None
    return None if sha256 is None else _table(rows, n_corners, *header, sha256)


def _comment_lines(buf: bytearray, pos: int, end: int, comments: list[str]) -> int | None:
    """Append the ``#`` lines at the start of ``buf[pos:end]``; where the first other line starts (None: odd bytes)."""
    while pos < end and buf[pos] == _HASH:
        stop = buf.find(b"\n", pos, end)
        stop = end if stop < 0 else stop
        line = bytes(buf[pos:stop])
        if not line.isascii() or any(b < _SPACE and b != 9 for b in line):  # CR, form feed...: lines split otherwise
            return None
        comments.append(line.decode("ascii"))
        pos = stop + 1
    return min(pos, end)


def comment_fields(comments: list[str]) -> tuple[dict[str, str], dict[str, str], bool]:
    """(failed views, metadata, header seen) of a file's ``#`` lines: the one reading both readers share."""
    failed: dict[str, str] = {}
    meta: dict[str, str] = {}
    saw_header = False
    for raw in comments:
        text = raw.strip()
        if text.startswith("##"):
            body = text[2:].strip()
            if body.startswith("failed "):
                name, _, reason = body[7:].partition(":")
                failed[name.strip()] = reason.strip()
            elif "=" in body:
                k, _, v = body.partition("=")
                meta[k.strip()] = v.strip()
        else:
            saw_header = saw_header or text.split()[1:4] == ["filename", "x", "y"]
    return failed, meta, saw_header


def _read_comments(comments: list[str]) -> tuple[dict[str, str], dict[str, str]] | None:
    """(failed views, metadata) of the ``#`` lines; None without the header."""
    failed, meta, saw_header = comment_fields(comments)
    return (failed, meta) if saw_header else None


def _read_rows(block: np.ndarray, begin: int, rows: _Rows, final: bool, has_dash: bool) -> bool:
    """Parse the whole rows of ``block[begin:]`` into ``rows``; False unless every one is simple.

    The bytes before ``begin`` are only read as the (ignored) left part of a
    number's window. ``has_dash``: the rows hold a ``-`` (without one, no
    corner is missing and no value negative).
    """
    if int(block[begin:].max()) >= 128:
        return False
    at = np.flatnonzero(block[begin:] <= _SPACE)
    kinds = block[begin:][at]
    at += begin
    if final and block[-1] != _NEWLINE:  # the file's last row without its line end
        at, kinds = np.append(at, len(block)), np.append(kinds, np.uint8(_NEWLINE))
    if len(at) % 4 or not len(at) or not (kinds.view(np.uint32) == _ROW_SEPARATORS).all():
        return False
    gaps = np.empty(len(at), np.int64)  # to the next separator: a field's length plus one
    np.subtract(at[1:], at[:-1], out=gaps[:-1])
    gaps[-1] = 2
    if int(gaps.min()) < 2 or at[0] == begin:  # an empty field or a blank line
        return False
    sep = at.reshape(-1, 4)  # shape (rows, 4): after the name, x, y and level
    lengths = gaps.reshape(-1, 4)  # shape (rows, 4): x, y, level and the next row's name, plus one
    n_rows = len(sep)
    if rows.count + n_rows > len(rows.xy):
        _reserve(rows, n_rows, (len(block) - begin) / n_rows)
    line_start = np.empty(n_rows, np.int64)
    line_start[0] = begin
    np.add(sep[:-1, 3], 1, out=line_start[1:])
    if (block[line_start] == _HASH).any():  # a comment between rows
        return False
    missing, x_negative, y_negative = _missing(block, sep, lengths) if has_dash else (None, None, None)
    xy = rows.xy[rows.count : rows.count + n_rows]
    numeric = slice(None) if missing is None else np.flatnonzero(~missing)
    if missing is not None:
        xy[missing] = np.nan
    out = xy if missing is None else np.empty((len(numeric), 2))
    for col, negative in ((0, x_negative), (1, y_negative)):
        if not _fixed_point(block, sep[numeric, col + 1], lengths[numeric, col] - 1, negative, out[:, col]):
            return False
    if missing is not None:
        xy[numeric] = out
    if not _runs(block, line_start, sep[:, 0] - line_start, missing, rows):
        return False
    rows.count += n_rows
    return True


def _reserve(rows: _Rows, n_rows: int, row_bytes: float) -> None:
    """Room for ``n_rows`` more rows, and for the rest of the file at 1.25 times its rate of rows per byte.

    The first block sets the size (rows of the same view are alike); a file
    whose rows get shorter later grows it again, at least doubling.
    """
    need = rows.count + n_rows
    guess = int(1.25 * rows.file_bytes / row_bytes) + n_rows
    xy = np.empty((max(need, guess, 2 * len(rows.xy)), 2))
    xy[: rows.count] = rows.xy[: rows.count]
    rows.xy = xy


def _missing(block: np.ndarray, sep: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray | None, ...]:
    """(missing rows, negative x, negative y) of the numeric rows, None for "none".

    A corner is missing when x or y is ``-`` or the level is ``-`` or ``-1``
    (whatever the other fields hold).
    """
    x_dash, y_dash, level_dash = (block[sep[:, k] + 1] == _MINUS for k in range(3))
    level_second = block[np.minimum(sep[:, 2] + 2, len(block) - 1)]
    missing = (x_dash & (lengths[:, 0] == 2)) | (y_dash & (lengths[:, 1] == 2))
    missing |= level_dash & ((lengths[:, 2] == 2) | ((lengths[:, 2] == 3) & (level_second == _ONE)))
    if not missing.any():
        return None, x_dash if x_dash.any() else None, y_dash if y_dash.any() else None
    numeric = ~missing
    return missing, x_dash[numeric], y_dash[numeric]


def _fixed_point(block: np.ndarray, end: np.ndarray, length: np.ndarray, negative: np.ndarray | None,
                 out: np.ndarray) -> bool:
    """Write into ``out`` the values of the tokens ending at ``end``; False unless all are ``[-]digits.digits``.

    One count of decimals for all (the first token's). Each token is read
    right-aligned in a window of the longest token's width, column by
    column: the digit columns form the integer mantissa by Horner's rule,
    columns left of a token's first digit are multiplied by zero, and any
    other byte inside a token (a second sign, an exponent, a letter) shows as
    a digit value of 10 or more. ``negative``: tokens starting with ``-``
    (None when none does).
    """
    if not len(end):
        return True
    width = int(length.max())
    first_token = bytes(block[end[0] - length[0] : end[0]])
    decimals = len(first_token) - 1 - first_token.rfind(b".")  # digits after the point, as in the first token
    point = width - 1 - decimals  # the point's column
    if width > _MAX_WIDTH or b"." not in first_token or not 0 < decimals < width - 1 or int(end.min()) < width:
        return False
    window = end - width  # each token's window starts here
    digits = _windows(block, window, width)  # shape (tokens, width)
    if not (digits[:, point] == _POINT).all():
        return False
    first = width - length  # column of each token's first digit
    if negative is not None:
        first += negative
    latest = int(first.max())
    if latest >= point:  # a token without a digit before the point
        return False
    digits -= _ZERO  # uint8: anything but a digit is now 10 or more
    digits[:, point] = 0
    for col in range(latest):  # columns where some token has not begun: zero there
        digits[:, col] *= first <= col
    if int(digits.max()) >= 10:
        return False
    # Horner's rule in integers: uint32 holds 9 digits (the common case), int64 up to 18
    mantissa = digits[:, 0].astype(np.uint32 if width - 1 <= 9 else np.int64)
    for col in range(1, width):
        if col != point:
            mantissa *= 10
            mantissa += digits[:, col]
    np.divide(mantissa, float(10**decimals), out=out)  # both exact doubles: the quotient is correctly rounded
    if negative is not None:
        np.negative(out, out=out, where=negative)
    return True


def _runs(block: np.ndarray, start: np.ndarray, length: np.ndarray, missing: np.ndarray | None, rows: _Rows) -> bool:
    """Record where a new name begins (a view's run of rows); False when a name is too close to the block's end.

    Names are compared as NUL-padded 8-byte words (a name never holds a
    NUL: a control byte ends a field, so padding cannot make two names equal).
    """
    width = int(length.max())
    words = -(-width // 8)
    if int(start.max()) + 8 * words > len(block):
        return False
    names = _windows(block, start, 8 * words)  # shape (rows, 8 * words): each name and what follows it
    if int(length.min()) == width:
        names[:, width:] = 0
    else:
        names[np.arange(8 * words) >= length[:, None]] = 0
    word = names.view(np.uint64)  # shape (rows, words)
    differ = word[1:, 0] ^ word[:-1, 0]
    for k in range(1, words):
        differ |= word[1:, k] ^ word[:-1, k]
    change = np.empty(len(start), bool)
    change[0] = bytes(block[start[0] : start[0] + length[0]]) != rows.last_name
    np.not_equal(differ, 0, out=change[1:])
    first = np.flatnonzero(change)
    rows.run_first.append(first + rows.count)
    rows.run_missing.append(np.zeros(len(first), bool) if missing is None else missing[first])
    rows.run_names += [bytes(block[s : s + n]).decode("ascii") for s, n in zip(start[first].tolist(), length[first].tolist())]
    rows.last_name = bytes(block[start[-1] : start[-1] + length[-1]])
    return True


def _windows(block: np.ndarray, start: np.ndarray, width: int) -> np.ndarray:
    """The ``width`` bytes from each of ``start``, shape (len(start), width), a copy.

    Gathered as one fixed-size item per row (numpy copies those twice as
    fast as rows of a sliding-window view); ``start + width`` must lie in the block.
    """
    items = np.ndarray((len(block) - width + 1,), f"V{width}", block, 0, (1,))
    return items[start].view(np.uint8).reshape(len(start), width)


def _table(rows: _Rows, n_corners: int, failed: dict[str, str], meta: dict[str, str], sha256: str) -> Simple | None:
    """The views of the rows when each is one run of ``n_corners`` rows, or one missing row; else None."""
    first_row = np.concatenate(rows.run_first)
    count = np.diff(np.append(first_row, rows.count))
    not_found = (count == 1) & np.concatenate(rows.run_missing)
    if not (not_found | (count == n_corners)).all() or len(set(rows.run_names)) < len(rows.run_names):
        return None  # a wrong corner count, or a view in two runs: the general reader explains or gathers
    xy = rows.xy[: rows.count]  # the capacity past it was never touched: it costs address space, not memory
    if not not_found.any():  # every view n_corners rows (missing corners are NaN rows): the rows are the array
        corners = xy.reshape(len(first_row), n_corners, 2)
    else:  # views not found are one row in the file and n_corners NaN rows here: copy the runs between them
        corners = np.empty((len(first_row), n_corners, 2))  # shape (K, N, 2)
        gaps = np.flatnonzero(not_found)
        for lo, hi in zip(np.concatenate([[0], gaps + 1]), np.concatenate([gaps, [len(first_row)]])):
            if hi > lo:
                corners[lo:hi] = xy[first_row[lo] : first_row[lo] + (hi - lo) * n_corners].reshape(hi - lo, n_corners, 2)
        corners[gaps] = np.nan
    for i in np.flatnonzero(not_found):
        failed.setdefault(rows.run_names[i], "board not found")
    return Simple(rows.run_names, corners, failed, meta, sha256)
