"""`lps demo --test min-step|settling`: an ASME B5.64 test on the simulated stage, end to end in seconds.

The paper camera 450 mm from its board (preset paper-closeup), corners
simulated at the point level: the incremental-step test on a stage with a
3 um dead band (2 um steps, 8 frames per stop: the report says it sticks),
or the settling test on a stage ringing 50 um at 8 Hz (frames 10 ms apart
after each move). Then the one estimate, the report and the test's lines.
"""
from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Callable

from lps_gui.core.planning.plan import Plan
from lps_gui.core.planning.presets import (
    PAPER_SPEC_TEST_LIMITS,
    asme_test_record,
    min_step_plan_fields,
    settling_plan_fields,
)
from lps_gui.core.truth.simulate import preset
from lps_gui.core.truth.stage_errors import Vibration
from lps_gui.pipeline.demos.run import DemoResult, DemoStep, prepare_out
from lps_gui.pipeline.demos.summary import PAPER_SPEC
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session

DEMO_DEAD_BAND_UM = 3.0
DEMO_FRAME_S = 0.01


def run_asme_demo(out: Path, test: str, seed: int = 0, say: Callable[[str], None] = lambda line: None) -> DemoResult:
    """Simulate, estimate and report one ASME B5.64 test into ``out`` (cleared if a previous demo made it)."""
    from lps_gui.report.pages.asme import test_lines
    from lps_gui.report.pdf.document import write_report

    out = Path(out).resolve()  # the result set's journal names its files relative to an absolute folder
    prepare_out(out)
    res = DemoResult(out)
    t0 = time.monotonic()
    spec = preset("paper-closeup", seed=seed)
    t = spec.plan.targets()
    if test == "min-step":
        errors = replace(spec.rig.errors, dead_band_um=DEMO_DEAD_BAND_UM)
        spec = replace(spec, plan=Plan(**min_step_plan_fields(float(t[0]), float(t[-1]))),
                       rig=replace(spec.rig, errors=errors))
        what = f"2 um steps on a stage with a {DEMO_DEAD_BAND_UM:g} um dead band"
    else:
        spec = replace(spec, plan=Plan(**settling_plan_fields(float(t[0]), float(t[-1]))), vibration=Vibration(),
                       frame_interval_s=DEMO_FRAME_S)
        what = "a stage ringing 50 um at 8 Hz after each move"
    session = simulate_point_session(spec, out / "session")
    session.meta["asme_test"] = asme_test_record(test)
    session.meta["stage_spec"] = {**PAPER_SPEC, **PAPER_SPEC_TEST_LIMITS}
    session.save_meta()
    res.session_dir = session.folder
    res.steps.append(DemoStep("simulate", "done", f"{len(session.records())} views of {what}", time.monotonic() - t0))
    say(f"simulate: {res.steps[-1].message}")
    t0 = time.monotonic()
    res.results = estimate_session(session.folder)
    res.steps.append(DemoStep("estimate", "done", "joint LM", time.monotonic() - t0))
    res.report_pdf = write_report(session.folder, res.results)
    res.csvs = [session.folder / n for n in ("positions.csv", "summary.csv") if (session.folder / n).exists()]
    say(f"report: {res.report_pdf}")
    res.summary = test_lines(res.results)
    return res
