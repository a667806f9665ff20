"""Issue 37: `lps compare` refuses two sessions of different rigs or travels with one line (it printed a PDF of dashes)."""
from dataclasses import replace

import pytest

from lps_gui.cli import main
from lps_gui.core.geometry.board import Board
from lps_gui.core.truth.simulate import small_spec
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    root = tmp_path_factory.mktemp("rigs")
    base = small_spec(seed=1, views=8, directions="both")
    specs = {"found": base,
             "left": small_spec(seed=1, views=8, directions="both", errors=StageErrorModel(periodic_um=0.5)),  # compensated: same rig, other errors
             "longer": small_spec(seed=1, views=10, directions="both"),
             "other_board": replace(base, rig=replace(base.rig, board=Board(cols=7, rows=5, square_mm=18.0)))}
    for name, spec in specs.items():
        simulate_point_session(spec, root / name)
        estimate_session(root / name)
    return root


def _compare(root, a, b, capsys):
    code = main(["compare", str(root / a), str(root / b), "--out", str(root / f"{a}-{b}.pdf")])
    return code, capsys.readouterr()


def test_compare_refuses_another_travel(sessions, capsys):
    code, out = _compare(sessions, "found", "longer", capsys)
    assert code != 0 and not (sessions / "found-longer.pdf").exists()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and "0-14 mm" in lines[0] and "0-18 mm" in lines[0], out.err


def test_compare_refuses_another_rig(sessions, capsys):
    code, out = _compare(sessions, "found", "other_board", capsys)
    assert code != 0 and not (sessions / "found-other_board.pdf").exists()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and "different rigs" in lines[0] and "board" in lines[0], out.err


@pytest.mark.gui
def test_compare_accepts_one_rig_before_and_after(sessions, capsys):
    code, out = _compare(sessions, "found", "left", capsys)
    assert code == 0 and (sessions / "found-left.pdf").exists(), out.err
