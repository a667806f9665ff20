"""As-found / as-left report from two estimated sessions."""
from __future__ import annotations

from dataclasses import replace

import pytest

from lps_gui.core.plan import Plan
from lps_gui.core.simulate import paper_rig_spec
from lps_gui.core.stage_errors import StageErrorModel
from lps_gui.errors import InputError
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session
from lps_gui.report.compare import comparison_figure, comparison_rows, improvement_factor, true_E_um, write_comparison


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    root = tmp_path_factory.mktemp("cmp")
    plan = Plan(start_mm=0.0, stop_mm=30.0, step_mm=1.5, directions="both", runs=1)
    out = []
    for name, errors in (("before", StageErrorModel(scale_ppm=80, periodic_um=6, backlash_um=12)),
                         ("after", StageErrorModel(periodic_um=0.5, backlash_um=1))):
        spec = replace(paper_rig_spec(seed=1, errors=errors, plan=plan), noise_px=0.023)
        simulate_point_session(spec, root / name)
        out.append((root / name, estimate_session(root / name)))
    return out


def test_rows_figure_and_pdf(pair, tmp_path):
    (bdir, before), (adir, after) = pair
    rows = comparison_rows(before, after)
    assert rows[0][0].startswith("positioning accuracy error E")
    assert float(rows[0][3].rstrip("x")) == pytest.approx(improvement_factor(before, after), rel=0.06)
    assert improvement_factor(before, after) > 5 and true_E_um(before) > 5 * true_E_um(after)
    fig = comparison_figure(before, after)
    assert {s.label for s in fig.series} == {"as found forward \u2191", "as found backward \u2193",
                                            "as left forward \u2191", "as left backward \u2193"}
    path = write_comparison(bdir, adir, tmp_path / "c.pdf")
    assert path.read_bytes().startswith(b"%PDF")
    with pytest.raises(InputError, match="folder not found"):
        write_comparison(bdir, adir, tmp_path / "nope" / "c.pdf")
