"""session.json targets and the SPEC 13 corners.vnl: round trips and one-line errors."""
from __future__ import annotations

import numpy as np
import pytest

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.targets import Target, pack_targets
from lps_gui.errors import InputError
from lps_gui.io.corners.target_vnl import (
    HEADER,
    empty_table,
    is_target_layout,
    read_target_corners,
    target_offsets,
    write_target_corners,
)
from lps_gui.io.targets_file import session_targets, targets_from_list, targets_to_list

CHARUCO = {"type": "charuco", "inner_corners": [10, 7], "square_mm": 30.0, "marker_mm": 22.0,
           "dictionary": "DICT_5X5_1000"}


def _spec(j: int, first: int, **extra) -> dict:
    return {"id": f"T{j}", **CHARUCO, "first_marker": first, **extra}


def test_targets_round_trip_through_session_json():
    items = [_spec(0, 0), _spec(1, 44, square_mm_uncertainty_um=2.0, scale_ppm=-15.0)]
    targets = targets_from_list(items)
    assert [t.n_markers for t in targets] == [44, 44]
    assert targets[1].marker_range == range(44, 88)
    assert targets_to_list(targets) == items
    assert session_targets({"targets": items}) == targets
    assert session_targets({"board": CHARUCO}) is None


@pytest.mark.parametrize("items,words", [
    ([_spec(0, 0), _spec(1, 43)], "set T1's first_marker to 44"),
    ([_spec(0, 0), _spec(0, 44)], "id T0 is used twice"),
    ([{**_spec(0, 0), "type": "chessboard"}], "targets must be charuco"),
    ([_spec(0, 990)], "has 1000"),
    ([_spec(0, -1)], "first_marker must be a whole number"),
    ([_spec(0, 1.5)], "first_marker must be a whole number"),
    ([{**_spec(0, 0), "colour": "red"}], "unknown field 'colour'"),
    ([_spec(0, 0, scale_ppm="x")], "scale_ppm must be a finite number"),
    ([{**_spec(0, 0), "id": "T 0"}], "without spaces"),
    ([], "the list is empty"),
    ("T0", "must be a list"),
])
def test_bad_targets_are_one_line_errors(items, words):
    with pytest.raises(InputError) as err:
        targets_from_list(items)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_session_with_board_and_targets_is_refused():
    with pytest.raises(InputError, match="both board and targets"):
        session_targets({"board": CHARUCO, "targets": [_spec(0, 0)]})


def test_same_first_marker_in_different_dictionaries_is_fine():
    a = _spec(0, 0)
    b = {**_spec(1, 0), "dictionary": "DICT_4X4_1000"}
    assert len(targets_from_list([a, b])) == 2


def _targets() -> list[Target]:
    return pack_targets([Board(4, 3, 20.0, type="charuco"), Board(5, 3, 15.0, type="charuco")])


def test_corners_round_trip_in_the_spec_13_layout(tmp_path):
    targets = _targets()
    table = empty_table(["a.png", "b.png", "c.png"], targets)
    rng = np.random.default_rng(0)
    table.corners_px[0, :12] = rng.uniform(0, 1000, (12, 2))
    table.corners_px[1, 14:20] = rng.uniform(0, 1000, (6, 2))
    table.failed["c.png"] = "no target found"
    table.meta["captures_sha256"] = "abc"
    path = tmp_path / "corners.vnl"
    write_target_corners(path, table)
    text = path.read_text().splitlines()
    assert text[0] == HEADER and "c.png - - - -" in text
    assert [line.split()[2] for line in text if line.startswith("b.png T1 ")] == ["2", "3", "4", "5", "6", "7"]
    assert is_target_layout(path)
    back = read_target_corners(path, targets)
    assert back.names == table.names and back.failed == table.failed and back.meta == table.meta
    np.testing.assert_allclose(back.corners_px, table.corners_px, atol=5e-5)
    np.testing.assert_array_equal(back.seen(), [[12, 0], [0, 6], [0, 0]])
    np.testing.assert_array_equal(target_offsets(targets), [0, 12, 27])
    assert back.target_corners(1).shape == (3, 15, 2)


@pytest.mark.parametrize("row,words", [
    ("a.png T9 0 1 2", "target 'T9' is not in session.json targets"),
    ("a.png T0 12 1 2", "corner 12 of T0 is outside 0-11"),
    ("a.png T0 x 1 2", "must be numbers"),
    ("a.png T0 1 nan 2", "not a pixel position"),
    ("a.png T0 1 2", "expected 'filename target corner x y'"),
])
def test_bad_corner_rows_name_the_line(tmp_path, row, words):
    path = tmp_path / "corners.vnl"
    path.write_text(f"{HEADER}\na.png T0 0 1.0 2.0\n{row}\n")
    with pytest.raises(InputError) as err:
        read_target_corners(path, _targets())
    assert words in str(err.value) and ":3:" in str(err.value)


def test_a_single_board_file_is_not_the_target_layout(tmp_path):
    path = tmp_path / "corners.vnl"
    path.write_text("# filename x y level\na.png - - -\n")
    assert not is_target_layout(path)
    with pytest.raises(InputError, match="first line must be"):
        read_target_corners(path, _targets())


def test_a_session_names_its_targets_instead_of_a_board(tmp_path):
    from lps_gui.core.geometry.camera_model import CameraIntrinsics
    from lps_gui.core.planning.plan import Plan
    from lps_gui.io.session import Session

    targets = _targets()
    intr = CameraIntrinsics.from_values((640, 480), 500.0, 500.0, 320.0, 240.0)
    s = Session.create(tmp_path / "s", targets, Plan(start_mm=0.0, stop_mm=10.0, step_mm=1.0), intr)
    again = Session.open(tmp_path / "s")
    assert "board" not in again.meta and again.targets() == targets
    with pytest.raises(InputError, match="names targets"):
        again.board()
    assert s.targets() == targets


def test_the_fast_reader_gives_what_the_line_by_line_reader_gives(tmp_path, monkeypatch):
    """Hand-edited files (views interleaved, extra spaces, comments between rows) read alike both ways."""
    import lps_gui.io.corners.target_vnl as module

    path = tmp_path / "corners.vnl"
    path.write_text(f"{HEADER}\n## failed c.png: no target found\nb.png  T1 3 10.5 20.25\na.png T0 0 1 2\n"
                    "# a comment\nc.png - - - -\nb.png T0 11 5 6\na.png T1 14 7.5 8.5\n")
    fast = read_target_corners(path, _targets())
    monkeypatch.setattr(module, "_regular_rows", lambda *args: None)
    slow = read_target_corners(path, _targets())
    assert fast.names == slow.names == ["b.png", "a.png", "c.png"] and fast.failed == slow.failed
    np.testing.assert_array_equal(fast.corners_px, slow.corners_px)
