"""The numpy corners.vnl reader and writer against the line-by-line ones they replaced (issue 15).

Every case is run through both: the bytes written must be identical, and
reading must give the same table (bit for bit, -0.0 included) or the same
error message (line number included), whichever of the library's two paths
reads it (the streaming fast path for the writer's form, the general reader
for anything else). The reference lives in ``corners_vnl_reference.py``.
"""
from __future__ import annotations

import hashlib

import numpy as np
import pytest

from lps_gui.errors import InputError
from lps_gui.io.corners.vnl import CornerTable, corners_vnl_bytes, read_corners_vnl, write_corners_vnl
from tests.io import corners_vnl_reference as ref


def _same_read(path, n_corners):
    """Both readers on one file: equal tables, or InputErrors with equal messages."""
    try:
        want = ref.read_corners_vnl(path, n_corners)
    except InputError as exc:
        with pytest.raises(InputError) as got:
            read_corners_vnl(path, n_corners)
        assert str(got.value) == str(exc)
        return None
    got = read_corners_vnl(path, n_corners)
    assert got.names == want.names
    assert got.failed == want.failed
    assert list(got.failed) == list(want.failed)
    assert got.meta == want.meta
    np.testing.assert_array_equal(got.corners_px, want.corners_px)
    finite = np.isfinite(want.corners_px)
    assert got.corners_px.dtype == np.float64
    assert (got.corners_px.view(np.int64)[finite] == want.corners_px.view(np.int64)[finite]).all()  # -0.0 too
    assert got.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    return got


def _table(rng, k=7, n=12):
    corners = rng.uniform(-50, 2500, (k, n, 2))
    corners[0, 3] = np.nan  # one corner missing
    corners[1, 5, 1] = np.inf  # half a corner non-finite: written as missing
    corners[2] = np.nan  # a view without corners and without a reason
    corners[3, :4] = [[-0.0, 0.03125], [-1e-9, 1.00005], [0.00005, 123456.78905], [9.99995, 99999.99995]]
    corners[4] = np.round(corners[4], 4)  # exact 4-decimal values (ties after scaling are common here)
    corners[5] = np.round(corners[5] * 2e4) / 2e4  # values at a half of the last printed digit
    names = [f"images/{i:06d}.png" for i in range(k)]
    names[6] = "x.png"  # names of different lengths
    return CornerTable(names, corners, failed={names[5]: "board not found\nat all"}, meta={"captures_sha256": "abc", "source": "test"})


@pytest.mark.parametrize("seed", range(5))
def test_written_bytes_are_identical_and_round_trip(tmp_path, seed):
    table = _table(np.random.default_rng(seed))
    assert corners_vnl_bytes(table).decode() == ref.format_corners_vnl(table)
    write_corners_vnl(tmp_path / "corners.vnl", table)
    back = _same_read(tmp_path / "corners.vnl", 12)
    assert back.names == table.names
    assert "images/000002.png" in back.failed and "images/000005.png" in back.failed


def test_many_random_values_format_like_python(tmp_path):
    rng = np.random.default_rng(1)
    values = np.concatenate([rng.uniform(-3000, 3000, 20000), rng.integers(-30000000, 30000000, 20000) / 2e4,
                             rng.integers(0, 10**6, 2000) / 1e4 + 5e-5])
    table = CornerTable(["a.png"], values.reshape(1, -1, 2))
    assert corners_vnl_bytes(table).decode() == ref.format_corners_vnl(table)


def test_empty_table(tmp_path):
    table = CornerTable([], np.zeros((0, 6, 2)))
    assert corners_vnl_bytes(table).decode() == ref.format_corners_vnl(table)


H = "# filename x y level\n"
CASES = {
    "plain": H + "a 1 2 0\na 3 4 0\nb 5 6 0\nb 7 8 0\n",
    "dashes and level -1": H + "a - - -\na 3 4 0\nb 5 6 -1\nb 7 8 0\n",
    "dash in one column": H + "a 1 - 0\na 3 4 0\nb - 6 0\nb 7 8 0\n",
    "level dash": H + "a 1 2 -\na 3 4 0\nb 5 6 0\nb 7 8 1\n",
    "three fields": H + "a 1 2\na 3 4\nb 5 6\nb 7 8\n",
    "extra fields": H + "a 1 2 0 extra\na 3 4 0 x y\nb 5 6 0\nb 7 8 0\n",
    "tabs, spaces, blank lines": H + "\n  a\t1  2 0  \n\na 3\t4\t0\n\t\nb 5 6 0\nb 7 8 0",
    "crlf": H.replace("\n", "\r\n") + "a 1 2 0\r\na 3 4 0\r\nb 5 6 0\r\nb 7 8 0\r\n",
    "lone cr": H + "a 1 2 0\ra 3 4 0\rb 5 6 0\rb 7 8 0\r",
    "form feed": H + "a 1 2 0\x0ca 3 4 0\nb 5 6 0\nb 7 8 0\n",
    "control bytes": H + "a\x01 1 2 0\na\x01 3 4 0\nb 5 6\x1f0\nb 7 8 0\x1f\n",
    "comments between rows": H + "a 1 2 0\n## source = x = y\na 3 4 0\n# a comment\n## failed c: not found: really\nb 5 6 0\nb 7 8 0\nc - - -\n",
    "failed view row": H + "a 1 2 0\na 3 4 0\nc - - -\nb 5 6 0\nb 7 8 0\n",
    "failed view listed": H + "## failed b: blurred\na 1 2 0\na 3 4 0\nb - - -\n",
    "interleaved views": H + "a 1 2 0\nb 5 6 0\na 3 4 0\nb 7 8 0\n",
    "header late": "a 1 2 0\na 3 4 0\n" + H,
    "header variant": "#  filename   x y\na 1 2 0\na 3 4 0\n",
    "scientific and signs": H + "a 1e3 -2.5E-2 0\na +3 .4 0\nb 5. 6_0 0\nb 7 8 0\n",
    "unicode name": H + "bild_\u00fc.png 1 2 0\nbild_\u00fc.png 3 4 0\n",
    "missing header": "a 1 2 0\na 3 4 0\n",
    "wrong header": "# name u v\na 1 2 0\na 3 4 0\n",
    "empty": "",
    "whitespace only": " \n\t\n",
    "header only": H,
    "comments only": H + "## source = x\n",
    "truncated": H + "a 1 2 0\na 3\n",
    "truncated name only": H + "a 1 2 0\na\nb 1 2 0\n",
    "non-numeric": H + "a 1 2 0\na 3 x 0\n",
    "non-numeric x": H + "a 1 2 0\na x 4 0\n",
    "nan": H + "a 1 2 0\na nan 4 0\n",
    "inf": H + "a 1 2 0\na 3 inf 0\n",
    "nan then non-numeric on one line": H + "a 1 2 0\na nan x 0\n",
    "non-numeric then nan on one line": H + "a 1 2 0\na x nan 0\n",
    "nan before truncated": H + "a nan 2 0\na 3\n",
    "truncated before nan": H + "a 3\na nan 2 0\n",
    "truncated before non-numeric": H + "a 3\na x 2 0\n",
    "non-numeric before truncated": H + "a x 2 0\na 3\n",
    "bad line then missing header": "a x 2 0\na 3 4 0\n",
    "too few corners": H + "a 1 2 0\nb 5 6 0\nb 7 8 0\n",
    "too many corners": H + "a 1 2 0\na 3 4 0\na 3 4 0\nb 5 6 0\nb 7 8 0\n",
    "second view wrong": H + "a 1 2 0\na 3 4 0\nb 5 6 0\n" + "c 1 2 0\n" * 3,
    "one missing row but board of 2": H + "a 1 2 0\na 3 4 0\nb 5 - 0\n",
}


def test_unreadable_files_give_the_same_errors(tmp_path):
    _same_read(tmp_path / "absent.vnl", 2)
    (tmp_path / "bad.vnl").write_bytes(H.encode() + b"a\xff 1 2 0\n")
    _same_read(tmp_path / "bad.vnl", 1)


def test_many_rows_across_parse_chunks(tmp_path, monkeypatch):
    """Chunk boundaries (made small here) must not split a view or lose a row."""
    import lps_gui.io.corners.vnl as fast

    monkeypatch.setattr(fast, "_CHUNK", 7)
    table = _table(np.random.default_rng(3), k=9, n=6)
    write_corners_vnl(tmp_path / "corners.vnl", table)
    assert (tmp_path / "corners.vnl").read_text() == ref.format_corners_vnl(table)
    _same_read(tmp_path / "corners.vnl", 6)
    text = (tmp_path / "corners.vnl").read_text().splitlines()
    text[30] = text[30].split()[0] + " 1.0 zz 0"
    (tmp_path / "bad.vnl").write_text("\n".join(text) + "\n")
    _same_read(tmp_path / "bad.vnl", 6)


# ----------------------------------------------------------------------------- the streaming fast path (issue 15)
# Files in the writer's fixed-point form are read by io/corners/vnl_fast.read_simple; anything it does not
# take must fall through to the general reader with the same table or the same message.

F = H + "## source = test\n"
FIXED = {
    "fixed plain": F + "a 1.5000 2.2500 0\na 3.0000 4.0625 0\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0\n",
    "fixed negative and minus zero": F + "a -1.5000 -0.0000 0\na 3.0000 -4.0625 0\nb -0.0000 6.0000 0\nb 7.0000 8.5000 0\n",
    "fixed missing rows": F + "a - - -\na 3.0000 4.0625 0\nb 5.1250 6.0000 -1\nb 7.0000 8.5000 0\n",
    "fixed one dash": F + "a 1.5000 - 0\na 3.0000 4.0625 0\nb - 6.0000 0\nb 7.0000 8.5000 0\n",
    "fixed dash and garbage": F + "a - zz 0\na 3.0000 4.0625 0\nb 5.1250 6.0000 -\nb 7.0000 8.5000 0\n",
    "fixed level other": F + "a 1.5000 2.2500 1\na 3.0000 4.0625 -2\nb 5.1250 6.0000 -1x\nb 7.0000 8.5000 0.5\n",
    "fixed failed view": F + "## failed c: blurred\na 1.5000 2.2500 0\na 3.0000 4.0625 0\nc - - -\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0\nd - - -\n",
    "fixed no final newline": F + "a 1.5000 2.2500 0\na 3.0000 4.0625 0\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0",
    "fixed crlf": (F + "a 1.5000 2.2500 0\na 3.0000 4.0625 0\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0\n").replace("\n", "\r\n"),
    "fixed cr in a comment": H + "## source = x\ry\na 1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed tab": F + "a 1.5000\t2.2500 0\na 3.0000 4.0625 0\n",
    "fixed tab in a comment": H + "##\tsource = x\t\na 1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed double space": F + "a 1.5000  2.2500 0\na 3.0000 4.0625 0\n",
    "fixed leading space": F + " a 1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed trailing space": F + "a 1.5000 2.2500 0 \na 3.0000 4.0625 0\n",
    "fixed trailing garbage": F + "a 1.5000 2.2500 0\na 3.0000 4.0625 0\n\x00\x00",
    "fixed blank line": F + "a 1.5000 2.2500 0\n\na 3.0000 4.0625 0\n",
    "fixed blank line after header": F + "\na 1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed three fields": F + "a 1.5000 2.2500\na 3.0000 4.0625\n",
    "fixed five fields": F + "a 1.5000 2.2500 0 x\na 3.0000 4.0625 0 y\n",
    "fixed truncated": F + "a 1.5000 2.2500 0\na 3.0000\n",
    "fixed comment between rows": F + "a 1.5000 2.2500 0\n## failed q: x\na 3.0000 4.0625 0\n",
    "fixed name starting with hash": F + "a 1.5000 2.2500 0\n#a 3.0000 4.0625 0\n",
    "fixed header late": "## source = x\na 1.5000 2.2500 0\na 3.0000 4.0625 0\n" + H,
    "fixed no header": "## source = x\na 1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed header only": F,
    "fixed other decimals": F + "a 1.5 2.25 0\na 3.0 4.0625 0\n",
    "fixed two decimals counts": F + "a 1.5000 2.25 0\na 3.0000 4.0625 0\n",
    "fixed exponent": F + "a 1.5000 2.2e10 0\na 3.0000 4.0625 0\n",
    "fixed exponent same width": F + "a 1.5000 2.25e1 0\na 3.0000 4.0625 0\n",
    "fixed nan": F + "a 1.5000 nan 0\na 3.0000 4.0625 0\n",
    "fixed inf": F + "a 1.5000 2.2500 0\na inf 4.0625 0\n",
    "fixed plus": F + "a +1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed two signs": F + "a --1.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed sign inside": F + "a 1-5.0000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed no integer digits": F + "a .5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed minus point": F + "a -.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed two points": F + "a 1.5.000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed letter": F + "a 1.5o00 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed long numbers": F + "a 12345678901.5000 2.2500 0\na 3.0000 123456789.0625 0\n",
    "fixed too long numbers": F + "a 1234567890123.5000 2.2500 0\na 3.0000 4.0625 0\n",
    "fixed wide and narrow": F + "a 1.5000 2.2500 0\na 1234.0000 4.0625 0\nb -1.1250 -1234.5678 0\nb 7.0000 8.5000 0\n",
    "fixed short first name": H + "a 1.5000 2.2500 0\na 12345.0000 4.0625 0\n",
    "fixed interleaved views": F + "a 1.5000 2.2500 0\nb 3.0000 4.0625 0\na 5.1250 6.0000 0\nb 7.0000 8.5000 0\n",
    "fixed view in two runs": F + "a 1.5000 2.2500 0\na 3.0000 4.0625 0\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0\na 1.0000 1.0000 0\na 1.0000 1.0000 0\n",
    "fixed too few corners": F + "a 1.5000 2.2500 0\nb 5.1250 6.0000 0\nb 7.0000 8.5000 0\n",
    "fixed too many corners": F + "a 1.5000 2.2500 0\na 1.5000 2.2500 0\na 1.5000 2.2500 0\n",
    "fixed names of two lengths": F + "ab 1.5000 2.2500 0\nab 3.0000 4.0625 0\nabc 5.1250 6.0000 0\nabc 7.0000 8.5000 0\n",
    "fixed name prefix": F + "images/000001.png 1.5000 2.2500 0\nimages/000001.png 3.0000 4.0625 0\n"
                         "images/000001.pn 5.1250 6.0000 0\nimages/000001.pn 7.0000 8.5000 0\n",
    "fixed unicode name": F + "bild_\u00fc.png 1.5000 2.2500 0\nbild_\u00fc.png 3.0000 4.0625 0\n",
    "fixed control byte in name": F + "a\x01 1.5000 2.2500 0\na\x01 3.0000 4.0625 0\n",
    "fixed only missing": F + "a - - -\nb - - -\n",
}


@pytest.mark.parametrize("name", list(CASES) + list(FIXED))
@pytest.mark.parametrize("n_corners", [1, 2])
def test_reader_matches_the_line_by_line_one(tmp_path, name, n_corners):
    """General cases (CASES) and the fast path's own (FIXED)."""
    path = tmp_path / "corners.vnl"
    path.write_bytes({**CASES, **FIXED}[name].encode("utf-8"))
    _same_read(path, n_corners)


def test_the_writers_files_take_the_fast_path(tmp_path):
    """Not a timing test: the common file must not fall back to the general reader unnoticed."""
    from lps_gui.io.corners.vnl_fast import read_simple

    table = _table(np.random.default_rng(7), k=9, n=12)
    write_corners_vnl(tmp_path / "corners.vnl", table)
    with open(tmp_path / "corners.vnl", "rb") as stream:
        simple = read_simple(stream, 12)
    assert simple is not None
    assert simple.names == table.names
    assert simple.sha256 == hashlib.sha256((tmp_path / "corners.vnl").read_bytes()).hexdigest()
    for name in ("fixed plain", "fixed negative and minus zero", "fixed missing rows", "fixed failed view",
                 "fixed no final newline", "fixed wide and narrow", "fixed names of two lengths"):
        (tmp_path / "case.vnl").write_bytes(FIXED[name].encode())
        with open(tmp_path / "case.vnl", "rb") as stream:
            assert read_simple(stream, 2) is not None, name


@pytest.mark.parametrize("block", [64, 97, 256])
def test_blocks_split_rows_and_comments_anywhere(tmp_path, monkeypatch, block):
    """Small read blocks: rows, comments and names cut at every place; a line longer than a block falls back."""
    import lps_gui.io.corners.vnl_fast as fast

    monkeypatch.setattr(fast, "_BLOCK", block)
    table = _table(np.random.default_rng(block), k=9, n=6)
    table.meta.update({f"sha256 images/{i:06d}.png": "ab" * 32 for i in range(9)})  # a long comment block
    write_corners_vnl(tmp_path / "corners.vnl", table)
    back = _same_read(tmp_path / "corners.vnl", 6)
    assert back.names == table.names
    for name in ("fixed failed view", "fixed no final newline", "fixed view in two runs", "fixed long numbers"):
        (tmp_path / "case.vnl").write_bytes(FIXED[name].encode())
        _same_read(tmp_path / "case.vnl", 2)
    # long rows first, then many short ones: the room guessed from the first block must grow
    long_then_short = F + "a_rather_long_image_name_0001.png 1234.5000 1000.2500 0\n" * 2 + "".join(f"v{i} - - -\n" for i in range(60))
    (tmp_path / "case.vnl").write_bytes(long_then_short.encode())
    assert len(_same_read(tmp_path / "case.vnl", 2).names) == 61


def test_mutated_files_match_the_line_by_line_reader(tmp_path):
    """Seeded fuzz: one or two bytes of a written file replaced by one that matters to a parser."""
    rng = np.random.default_rng(15)
    interesting = b" \t\r\n\x00\x0c-+.eE#0159xn"
    table = _table(rng, k=7, n=6)
    clean = corners_vnl_bytes(table)
    start = clean.index(b"\nimages") + 1
    path = tmp_path / "corners.vnl"
    for _ in range(300):
        data = bytearray(clean)
        for at in rng.integers(start - 5, len(data), rng.integers(1, 3)):
            data[at] = interesting[rng.integers(len(interesting))]
        path.write_bytes(bytes(data))
        _same_read(path, 6)
