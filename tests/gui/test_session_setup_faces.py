"""One capture set-up, two faces (issue 34): `lps capture`'s switches and the GUI's capture panel, given the
same inputs, write the same session.json (lps_gui.capture.setup.SessionSetup behind both)."""
from __future__ import annotations

import shutil

import pytest

from lps_gui.capture.setup import apply_setup
from lps_gui.cli import build_parser
from lps_gui.cli.capture.plan import line_plan
from lps_gui.cli.capture.setup import setup_meta
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import preset
from lps_gui.io.session import Session
from lps_gui.io.setup_fields import ENV_FIELDS, ID_FIELDS

pytestmark = pytest.mark.gui

ENV = {f.key: round(f.lo + 1.25 + i, f.decimals) for i, f in enumerate(ENV_FIELDS)}  # a value inside each range
IDENT = {f.key: f"{f.label} {i}" for i, f in enumerate(ID_FIELDS)}
NOTES = "PT100 taped to the board"
RANGE = ["--start", "0", "--stop", "8"]


def cli_args(*extra: str):
    argv = ["capture", "--out", "unused", "--spec", "paper", "--env-notes", NOTES, "--test", "min-step", *RANGE]
    for f in ENV_FIELDS:
        argv += [f.flag, str(ENV[f.key])]
    for f in ID_FIELDS:
        argv += [f.flag, IDENT[f.key]]
    return build_parser().parse_args(argv + list(extra))  # the last of a switch given twice wins


def gui_panel(window):
    cap = window.capture_panel
    cap.set_plan(Plan(start_mm=0.0, stop_mm=8.0, step_mm=2.0, directions="+", runs=1))
    box = cap.report_setup
    box.select_preset("paper")
    for f in ENV_FIELDS:
        box.env[f.key].setValue(ENV[f.key])
    box.notes.setText(NOTES)
    for f in ID_FIELDS:
        box.ident[f.key].setText(IDENT[f.key])
    cap.asme_test.setCurrentIndex(cap.asme_test.findData("min-step"))
    return cap


def test_cli_and_gui_write_the_same_session_json(window, tmp_path):
    spec = preset("small")
    Session.create(tmp_path / "base", spec.rig.board, spec.plan)
    cli_meta, gui_meta = setup_meta(cli_args()), gui_panel(window).session_setup().meta()
    for name, meta in (("cli", cli_meta), ("gui", gui_meta)):
        shutil.copytree(tmp_path / "base", tmp_path / name)
        apply_setup(Session.open(tmp_path / name), meta)
    cli_file, gui_file = ((tmp_path / n / "session.json").read_bytes() for n in ("cli", "gui"))
    assert cli_file == gui_file
    # every field reached the file (a face that dropped one would agree with nothing)
    assert cli_meta["stage_spec"] == {"accuracy_um": 20.0, "repeatability_um": 5.0, "straightness_um": 38.0}
    assert cli_meta["environment"] == {**ENV, "notes": NOTES}
    assert cli_meta["identification"] == IDENT
    assert cli_meta["asme_test"] == {"test": "min-step", "step_um": 2.0}


def test_cli_and_gui_plan_the_same_test(window):
    cap = gui_panel(window)
    gui_plan, cli_plan = cap.plan(), line_plan(cli_args("--step", "2"))
    for field in ("targets_mm", "directions", "runs", "frames_per_stop"):
        assert getattr(gui_plan, field) == getattr(cli_plan, field), field
    assert len(cli_plan.targets_mm) > 10


def test_a_bad_entry_is_refused_alike(window):
    from lps_gui.errors import InputError

    with pytest.raises(InputError, match="board_temperature_c"):
        setup_meta(cli_args("--board-temp", "400"))
    box = gui_panel(window).report_setup
    box.env["board_temperature_c"].setMaximum(500.0)
    box.env["board_temperature_c"].setValue(400.0)
    with pytest.raises(InputError, match="board_temperature_c"):
        box.meta()
