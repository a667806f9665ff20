"""The numpy corners.vnl reader and writer against the line-by-line ones they replaced (issue 15).

Every case is run through both: the bytes written must be identical, and
reading must give the same table or the same error message (line number
included). The reference lives in ``corners_vnl_reference.py``.
"""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.errors import InputError
from lps_gui.io.corners_vnl import CornerTable, corners_vnl_bytes, read_corners_vnl, write_corners_vnl
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


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("n_corners", [1, 2])
def test_reader_matches_the_line_by_line_one(tmp_path, name, n_corners):
    path = tmp_path / "corners.vnl"
    path.write_bytes(CASES[name].encode("utf-8"))
    _same_read(path, n_corners)


def test_unreadable_files_give_the_same_errors(tmp_path):
    _same_read(tmp_path / "absent.vnl", 2)
    (tmp_path / "bad.vnl").write_bytes(H.encode() + b"a\xff 1 2 0\n")
    _same_read(tmp_path / "bad.vnl", 1)


def test_many_rows_across_parse_chunks(tmp_path, monkeypatch):
    """Chunk boundaries (made small here) must not split a view or lose a row."""
    import lps_gui.io.corners_vnl as fast

    monkeypatch.setattr(fast, "_CHUNK", 7)
    table = _table(np.random.default_rng(3), k=9, n=6)
    write_corners_vnl(tmp_path / "corners.vnl", table)
    assert (tmp_path / "corners.vnl").read_text() == ref.format_corners_vnl(table)
    _same_read(tmp_path / "corners.vnl", 6)
    text = (tmp_path / "corners.vnl").read_text().splitlines()
    text[30] = text[30].split()[0] + " 1.0 zz 0"
    (tmp_path / "bad.vnl").write_text("\n".join(text) + "\n")
    _same_read(tmp_path / "bad.vnl", 6)
