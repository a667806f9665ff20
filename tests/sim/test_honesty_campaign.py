"""benchmarks/honesty.py's short form (issue 35): one rendered session with realism on, end to end, scored against
the truth; the full campaign (10 seeds of every kind) is a benchmark, its table in docs/validation.md."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_the_short_campaign_scores_a_rendered_session_with_realism_on(tmp_path):
    out = tmp_path / "honesty.json"
    md = tmp_path / "honesty.md"
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "honesty.py"), "--short", "--out",
                           str(tmp_path / "work"), "--json", str(out), "--md", str(md)],
                          capture_output=True, text=True, timeout=200)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    doc = json.loads(out.read_text())
    [s] = doc["sessions"]
    assert (s["kind"], s["stage"], s["realism"], s["seed"]) == ("line-both", "flat", "on", 0)
    assert s["rms_px"] > 0.03  # the lens misfit and the noise over the frame show in the residuals
    figures = {c["figure"] for c in s["figures"]}
    assert {"E", "M", "B", "scale", "max |deviation|"} <= figures, figures
    assert {f["finding"] for f in s["findings"]} >= {"EAX", "EBX", "ECX", "straightness v1"}
    assert s["position_z_ms"] is not None and s["self_check"] is not None
    pooled = {(f["figure"]) for f in doc["figures"]}
    assert "per-stop position" in pooled and "E" in pooled
    text = md.read_text()
    assert "coverage of U (k=2)" in text and "| line-both | flat | on | E | 1 |" in text
    assert not list((tmp_path / "work").iterdir())  # sessions cleared after scoring


def test_a_row_declares_the_print_scale_its_prints_are_drawn_from():
    """The realism draws each print's scale from what the session declares (core/truth/realism.py): a row
    declared 2 um a square (100 ppm) over prints drawn at 10 ppm (none with realism off), and its U of max
    |deviation| was 80-95 % print-scale rows no truth could test (mean z^2 0.06-0.45 over 10 seeds)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("honesty", ROOT / "benchmarks" / "honesty.py")
    honesty = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(honesty)
    on, off = honesty.build_spec("row", "flat", "on", 0), honesty.build_spec("row", "flat", "off", 0)
    square = on.layout.targets[0].board.square_mm
    assert honesty.campaign_environment(on)["square_mm_uncertainty_um"] == (
        1e-3 * on.realism.print_scale_ppm * square)
    assert honesty.campaign_environment(off)["square_mm_uncertainty_um"] <= 0.1  # the line's certificate
    assert honesty.campaign_environment(off)["board_cte_ppm_per_k"] == 23.0  # a row's environment otherwise
    two_depth = honesty.build_spec("two-depth", "flat", "on", 0)  # two depths alike (its 2 um hid a failing cell)
    assert honesty.campaign_environment(two_depth)["square_mm_uncertainty_um"] == pytest.approx(
        1e-3 * two_depth.realism.print_scale_ppm * two_depth.rig.board.square_mm)


def test_rows_and_two_depths_declare_no_temperature_error_the_simulator_does_not_render():
    """The simulator has no temperature (board and stage at 20 C exactly, no thermometer error drawn): a declared
    0.5 K thermometer and an uncorrected 20.5 C stage were budget rows no truth could test, 31-90 % of the U of a
    row's or a two-depth constellation's scale and max |deviation| (docs/validation.md, hon-rows)."""
    import importlib.util

    import numpy as np

    from lps_gui.core.metrology.environment import Environment
    from lps_gui.core.metrology.uncertainty_budget import BudgetInputs, budget_rows

    spec = importlib.util.spec_from_file_location("honesty", ROOT / "benchmarks" / "honesty.py")
    honesty = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(honesty)
    x = BudgetInputs(travel_mm=300.0, square_mm=30.0, sigma_px=0.02, sigma_um=np.full(12, 1.0),
                     sigma_total_um=np.full(12, 1.0))
    for kind in ("row", "two-depth"):
        env = Environment.from_dict(honesty.campaign_environment(honesty.build_spec(kind, "motions", "on", 0)))
        temperature = {r.source: r.contribution_um for r in budget_rows(x, env) if "temperature" in r.source}
        assert set(temperature) == {"board temperature", "stage temperature"}, temperature
        assert all(c == 0.0 for c in temperature.values()), (kind, temperature)


def test_pooled_runs_let_a_later_runs_cells_replace_an_earlier_runs(tmp_path):
    """`--pool`: a cell re-scored by newer code supersedes that cell's old scores; the other cells stay as they were."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("honesty", ROOT / "benchmarks" / "honesty.py")
    honesty = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(honesty)

    def row(kind, seed, z):
        return {"kind": kind, "stage": "flat", "realism": "off", "seed": seed, "position_z_ms": z}

    old, new = tmp_path / "old.json", tmp_path / "new.json"
    old.write_text(json.dumps({"sessions": [row("row", 0, 5.0), row("row", 1, 5.0), row("planar", 0, 1.0),
                                            {"kind": "x", "stage": "", "realism": "", "seed": -1, "error": "boom"}]}))
    new.write_text(json.dumps({"sessions": [row("row", 0, 1.1)]}))
    pooled = honesty.pooled_runs([old, new])
    assert sorted((s["kind"], s["seed"], s["position_z_ms"]) for s in pooled) == [("planar", 0, 1.0), ("row", 0, 1.1)]
