"""As-found / as-left on the simulated rig: measure, compensate, re-capture, re-measure.

From an estimated simulated session (the as-found) the compensation table is
built, the same rig captures the same plan again with the engine commanding
every target through the table's inverse (what our capture engine does), and the
new session is detected and estimated (the as-left). The simulator's truth
says how far the stage really was from the nominal before and after.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lps_gui.core.progress import CancelToken, ProgressFn, no_progress
from lps_gui.core.truth.simulation_spec import SimulationSpec
from lps_gui.errors import InputError
from lps_gui.io.results.iso_e import session_E_um, true_E_um
from lps_gui.io.session import Session

TABLE_FILE = "compensation.csv"
CARRIED_META = ("stage_spec", "environment", "identification")  # as left is judged like as found


@dataclass
class PassResult:
    """The as-left session and the systematic error E (ISO 230-2, um) before and after, true and measured."""

    after_dir: Path
    true_E_before_um: float
    true_E_after_um: float
    measured_E_before_um: float
    measured_E_after_um: float
    plane_E_before_um: float  # true, at the board plane: what the camera measures (README: Abbe offset)
    plane_E_after_um: float
    entry_sigma_um: float  # median sigma of a table entry: the measurement's own noise

    @property
    def improvement(self) -> float:
        """Of the true E (what the compensation achieved; the simulator knows it)."""
        return self.true_E_before_um / max(self.true_E_after_um, 1e-9)

    @property
    def measured_improvement(self) -> float:
        """Of the measured E (results.json's, the noise taken out: what `lps compare` reports)."""
        return self.measured_E_before_um / max(self.measured_E_after_um, 1e-9)

    def lines(self) -> list[str]:
        return [
            f"as found: E {self.measured_E_before_um:.2f} \u00b5m measured, {self.true_E_before_um:.2f} \u00b5m true",
            f"  (true at the board plane {self.plane_E_before_um:.2f} \u00b5m)",
            f"as left (compensated): E {self.measured_E_after_um:.2f} \u00b5m measured, "
            f"{self.true_E_after_um:.2f} \u00b5m true",
            f"  (true at the board plane {self.plane_E_after_um:.2f} \u00b5m)",
            f"improvement of true E {self.improvement:.1f}x, of measured E {self.measured_improvement:.1f}x; "
            f"table entry sigma {self.entry_sigma_um:.2f} \u00b5m",
        ]


def as_left_spec(before: Session) -> SimulationSpec:
    """The as-left capture's rig: ``before``'s stage and board, its prints (the same board stays on the stage), and
    image noise and repeatability draws of its own, independent of every other seed's session."""
    from lps_gui.sim.session import spec_of_session

    if not (before.truth or {}).get("simulated"):
        raise InputError(f"{before.folder}: not captured on the simulated rig; re-capture a real stage with `lps capture --compensation`")
    return spec_of_session(before).recaptured()


def compensation_pass(
    before_dir: Path | str,
    after_dir: Path | str,
    progress: ProgressFn = no_progress,
    cancel: CancelToken | None = None,
) -> PassResult:
    """Re-capture ``before_dir``'s plan on its simulated rig through its compensation table into ``after_dir``."""
    from lps_gui.capture.compensated import apply_compensation
    from lps_gui.io.compensation_file import write_table
    from lps_gui.pipeline.compensate import session_results, table_from_results
    from lps_gui.pipeline.detect import detect_session
    from lps_gui.pipeline.estimate import estimate_session
    from lps_gui.sim.session import create_simulated_session, simulated_engine

    before = Session.open(before_dir)
    spec = as_left_spec(before)
    results_before = session_results(before.folder)
    table = table_from_results(results_before)
    cam = (before.truth or {}).get("camera") or {}
    session, stage, camera = create_simulated_session(after_dir, spec, noise_grey=float(cam.get("noise_grey", 2.0)),
                                                      intrinsics=before.meta.get("intrinsics"))
    carried = {k: before.meta[k] for k in CARRIED_META if k in before.meta}  # the same stage, board and room
    if carried:
        session.meta.update(carried)
        session.save_meta()
    table_path = write_table(session.folder / TABLE_FILE, table, "csv")
    stage.connect()
    engine = simulated_engine(session, stage, camera)
    apply_compensation(engine, session, table_path)
    try:
        summary = engine.run(progress, cancel)
    finally:
        camera.close()
        stage.disconnect()
    if summary.listed < summary.total:
        raise InputError(f"compensated capture stopped after {summary.listed}/{summary.total} frames: {summary.error or summary.state}")
    detect_session(session.folder, cancel=cancel)
    results_after = estimate_session(session.folder, cancel=cancel)
    sig = np.r_[table.sigma_plus_um, table.sigma_minus_um]
    return PassResult(
        after_dir=session.folder,
        true_E_before_um=true_E_um(results_before),
        true_E_after_um=true_E_um(results_after),
        measured_E_before_um=session_E_um(results_before),
        measured_E_after_um=session_E_um(results_after),
        entry_sigma_um=float(np.median(sig)),
        plane_E_before_um=session_E_um(results_before, "truth_plane_deviation_um"),
        plane_E_after_um=session_E_um(results_after, "truth_plane_deviation_um"),
    )
