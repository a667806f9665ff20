"""Compensated capture: targets commanded through the table's inverse land on the nominal (issue 12)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lps_gui.capture.compensated import apply_compensation
from lps_gui.core.metrology.compensation import CompensationTable
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.simulate import preset
from lps_gui.core.truth.stage_errors import StageErrorModel
from lps_gui.io.compensation_file import write_table
from lps_gui.sim.rig import spec_for_plan
from lps_gui.sim.session import create_simulated_session, simulated_engine
from lps_gui.sim.truth import read_truth

ERRORS = StageErrorModel(scale_ppm=80.0, periodic_um=6.0, pitch_mm=5.0, periodic_phase_rad=0.7, backlash_um=12.0,
                         repeatability_um=0.3)


def rig_spec(preset_name: str, plan: Plan, errors: StageErrorModel = ERRORS):
    spec = spec_for_plan(preset_name, plan, seed=5)
    return replace(spec, rig=replace(spec.rig, errors=errors))


def capture(folder, spec, table_path=None):
    session, stage, camera = create_simulated_session(folder, spec)
    stage.connect()
    engine = simulated_engine(session, stage, camera)
    apply_compensation(engine, session, table_path)
    summary = engine.run()
    stage.disconnect()
    assert summary.state == "done"
    return session


def test_engine_commands_through_the_inverse_and_records_it(tmp_path):
    plan = Plan(start_mm=0.0, stop_mm=20.0, step_mm=2.5, directions="both", runs=1)
    spec = rig_spec("small", plan)
    x = np.linspace(-5, 30, 141)  # 0.25 mm: linear interpolation of the 5 mm periodic error within 0.07 um
    truth_table = CompensationTable(  # the error model itself: a perfect measurement
        x, x + 1e-3 * ERRORS.positioning_error_um(x, 1), x + 1e-3 * ERRORS.positioning_error_um(x, -1),
        np.zeros_like(x), np.zeros_like(x), True)
    path = write_table(tmp_path / "t.csv", truth_table, "csv")
    session = capture(tmp_path / "s", spec, path)
    records = session.records()
    truth = read_truth(session)
    commanded = np.array([r.commanded_mm for r in records])
    target = np.array([r.target_mm for r in records])
    d = np.array([1 if r.direction == "+" else -1 for r in records])
    np.testing.assert_allclose(commanded, [truth_table.command_mm(t, s) for t, s in zip(target, d)], atol=1e-6)  # CSV keeps 1 nm
    assert np.max(np.abs(commanded - target)) > 0.008
    axis = np.array([truth[r.index]["axis_mm"] for r in records])
    assert np.max(np.abs(axis - target)) * 1e3 < 4 * ERRORS.repeatability_um  # systematic error gone
    assert session.meta["compensation"]["table"]["nominal_mm"][0] == -5.0
    uncompensated = capture(tmp_path / "u", spec)
    assert all(r.commanded_mm is None for r in uncompensated.records())
    assert '"commanded_mm"' not in (uncompensated.folder / "captures.jsonl").read_text()


@pytest.mark.slow
def test_compensated_recapture_reduces_true_E_5x(tmp_path):
    """Must show: as found -> table -> as left on the rendered paper rig, 41 targets x 2 directions."""
    from lps_gui.pipeline.compensation_pass import compensation_pass
    from lps_gui.pipeline.detect import detect_session
    from lps_gui.pipeline.estimate import estimate_session

    plan = Plan(start_mm=0.0, stop_mm=40.0, step_mm=1.0, directions="both", runs=1, overshoot_mm=2.0)
    before = capture(tmp_path / "before", rig_spec("paper-rig", plan, replace(preset("paper-rig").rig.errors,
                     scale_ppm=80.0, periodic_um=6.0, periodic_phase_rad=0.7, backlash_um=12.0)))
    detect_session(before.folder)
    estimate_session(before.folder)
    res = compensation_pass(before.folder, tmp_path / "after")
    print(*res.lines(), sep="\n")
    from lps_gui.report.pdf.compare import write_comparison

    assert write_comparison(before.folder, res.after_dir).stat().st_size > 1000  # the as-found/as-left PDF
    assert res.true_E_before_um > 20.0
    assert res.improvement >= 5.0
    # down to the noise of the measurement where the camera measures (the board plane, README "Abbe offset")
    assert res.plane_E_after_um < 6 * res.entry_sigma_um
    assert res.measured_E_after_um < 6 * res.entry_sigma_um


def test_grbl_sender_corrects_through_the_emulator(tmp_path):
    """GRBL has no compensation: the engine sends the corrected targets over the real GRBL protocol."""
    from lps_gui.sim.emulated import emulated_rig_stage
    from tests.capture.helpers import tiny_spec

    plan = Plan(start_mm=0.0, stop_mm=4.0, step_mm=2.0, directions="both", overshoot_mm=1.0, settle_s=0.0, feed_mm_min=1200.0)
    x = np.linspace(-2.0, 6.0, 5)
    table = CompensationTable(x, x + 0.004, x + 0.002, np.zeros(5), np.zeros(5), True)
    session, rig_stage, camera = create_simulated_session(tmp_path / "emulated", tiny_spec(plan))
    stage = emulated_rig_stage(rig_stage, time_scale=50.0)
    try:
        engine = simulated_engine(session, stage, camera)
        apply_compensation(engine, session, write_table(tmp_path / "t.csv", table, "csv"))
        assert engine.run().state == "done"
    finally:
        stage.disconnect()
    recs = session.records()
    want = [r.target_mm - (0.004 if r.direction == "+" else 0.002) for r in recs]
    assert [r.commanded_mm for r in recs] == pytest.approx(want, abs=1e-6)
    assert [r.reported_mm for r in recs] == pytest.approx(want, abs=2e-3)  # GRBL reports where it was sent (3 decimals)


def test_the_as_left_draws_its_own_noise_on_the_same_print(tmp_path):
    """Must show: the as-left capture replays no other seed's image noise or repeatability (seed + 1 did: the
    campaign's compensated seed k was line-both seed k + 1's draws), and with realism on it measures the print the
    table was made with, also when its rig is rebuilt from its session.json (``--resume``)."""
    from lps_gui.core.truth.realism import realism_named
    from lps_gui.io.session import Session
    from lps_gui.pipeline.compensation_pass import as_left_spec
    from lps_gui.sim.rig import make_simulated_rig
    from lps_gui.sim.session import spec_of_session
    from tests.capture.helpers import tiny_spec

    spec = replace(tiny_spec(seed=3), realism=realism_named("on"))
    before = create_simulated_session(tmp_path / "before", spec)[0]
    after_spec = as_left_spec(Session.open(before.folder))
    after = create_simulated_session(tmp_path / "after", after_spec)[0]

    def draws(s, key: int = 4) -> np.ndarray:  # the stage's repeatability and the camera's noise draws of capture key
        stage, camera = make_simulated_rig(s)
        stage.seed_capture(key)
        camera.seed_capture(key)
        return np.r_[stage._rng.standard_normal(3), camera._rng.standard_normal(3)]

    mine = draws(after_spec)
    for seed in range(12):  # the campaign's seeds and the next ones
        assert not np.allclose(mine, draws(replace(spec, seed=seed))), f"the as-left replays seed {seed}'s draws"
    printed = [(b.square_mm, b.warp_mm) for b in (spec.printed(), after_spec.printed(),
                                                   spec_of_session(Session.open(after.folder)).printed())]
    assert printed[1] == printed[0] and printed[2] == printed[0]
    assert after.truth["realism"]["printed"] == before.truth["realism"]["printed"]
