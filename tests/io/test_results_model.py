"""results.json read once into typed sections: nothing lost, one-line errors naming the field, new sections kept."""
from __future__ import annotations

import copy
import dataclasses
import json

import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.simulate import small_spec
from lps_gui.errors import InputError
from lps_gui.io.jsonfile import json_bytes
from lps_gui.io.results_model import Results, as_results, read_results
from lps_gui.io.results_sections import Uncertainty
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def estimated(tmp_path_factory):
    """{"line": folder, "planar": folder}: simulated point sessions estimated by the one path (a few seconds)."""
    root = tmp_path_factory.mktemp("results-model")
    simulate_point_session(small_spec(seed=3, views=12, directions="both", runs=2), root / "line")
    estimate_session(root / "line")
    assert lps_main(["simulate", "--planar", "--points", str(root / "planar"), "--preset", "small-planar",
                     "--directions", "both", "--runs", "2", "--seed", "4"]) == 0
    estimate_session(root / "planar")
    return {"line": root / "line", "planar": root / "planar"}


def _document(folder) -> dict:
    return json.loads((folder / "results.json").read_text())


@pytest.mark.parametrize("kind", ["line", "planar"])
def test_round_trip_gives_the_file_back_byte_for_byte(estimated, kind):
    path = estimated[kind] / "results.json"
    results = read_results(estimated[kind])
    assert json_bytes(results.to_dict()) == path.read_bytes()
    assert results.source == str(path) and results.extra == {}
    d = _document(estimated[kind])
    assert results.planar == (kind == "planar") and results.axes == tuple(d.get("axes", ["X"]))
    assert [p.index for p in results.positions] == [p["index"] for p in d["positions"]]
    assert results.parameters.n_used == d["parameters"]["n_used"]
    assert results.parameters.reference_index == d["parameters"]["reference_index"]
    assert results.environment.square_mm_used == d["environment"]["square_mm_used"]
    assert results.truth_comparison.position_rms_error_um == d["truth_comparison"]["position_rms_error_um"]
    if kind == "line":
        assert results.figures.single_run.scale_ppm == d["figures"]["single_run"]["scale_ppm"]
        assert results.figures.iso230_2.get("A_um") == d["figures"]["iso230_2"]["A_um"]
        assert results.figures.straightness.v2.resolved == d["figures"]["straightness"]["v2"]["resolved"]
        assert results.uncertainty.u_k2("A_um") == d["uncertainty"]["figures_k2"]["A_um"]
        assert [b.source for b in results.uncertainty.budget] == [b["source"] for b in d["uncertainty"]["budget"]]
    else:
        pl = d["figures"]["planar"]
        assert results.figures.planar.squareness_urad == pl["squareness_urad"]
        assert results.figures.planar.per_axis["Y"].lines == pl["per_axis"]["Y"]["lines"]
        assert len(results.figures.planar.nodes) == len(pl["nodes"])
        assert results.uncertainty.per_axis["X"].expanded_k2_um == d["uncertainty"]["per_axis"]["X"]["expanded_k2_um"]
        assert results.truth_comparison.per_coordinate_rms_error_um == tuple(
            d["truth_comparison"]["per_coordinate_rms_error_um"])


@pytest.mark.slow
@pytest.mark.parametrize("planar", [False, True])
def test_round_trip_of_the_quick_demo(tmp_path, planar):
    from lps_gui.pipeline.demo import run_demo

    res = run_demo(tmp_path / "out", quick=True, planar=planar)
    path = res.session_dir / "results.json"
    assert json_bytes(read_results(path).to_dict()) == path.read_bytes()
    assert res.results.planar == planar


def test_optional_sections_are_none_and_lists_tuples(estimated):
    d = _document(estimated["line"])
    for name in ("environment", "uncertainty", "truth_comparison", "flags", "intrinsics"):
        d.pop(name)
    d["figures"]["iso230_2"] = None
    results = Results.from_dict(d)
    assert results.environment is None and results.uncertainty is None and results.truth_comparison is None
    assert results.intrinsics is None and results.figures.iso230_2 is None and results.flags == ()
    assert results.to_dict() == d  # nothing added that was not there


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.pop("format"), "'format'"),
    (lambda d: d["positions"][2].pop("index"), "'positions[2].index'"),
    (lambda d: d["figures"]["single_run"].update(scale_ppm="large"), "'figures.single_run.scale_ppm'"),
    (lambda d: d.update(parameters=[1, 2]), "'parameters'"),
    (lambda d: d["uncertainty"]["budget"][1].pop("source"), "'uncertainty.budget[1].source'"),
    (lambda d: d["positions"][3].update(measured_mm=float("nan")), "position 3 (measured_mm)"),
])
def test_a_wrong_or_old_document_is_a_one_line_error_naming_the_file_and_the_field(estimated, tmp_path, edit, field):
    d = _document(estimated["line"])
    edit(d)
    (tmp_path / "results.json").write_text(json.dumps(d))
    with pytest.raises(InputError) as info:
        read_results(tmp_path)
    message = str(info.value)
    assert "\n" not in message and field in message and str(tmp_path / "results.json") in message, message
    assert "lps estimate" in message


def test_no_positions_is_refused(estimated):
    d = _document(estimated["line"])
    d["positions"] = []
    with pytest.raises(InputError, match="no per-position table"):
        Results.from_dict(d, source="r.json")


def test_unknown_sections_and_keys_are_kept(estimated):
    d = _document(estimated["planar"])
    d["thermal_drift"] = {"count": 3, "per_target": [{"name": "T1", "scale_ppm": 1.5}]}  # a section from a later version
    d["figures"]["error_motions"] = {"roll_urad": [1.0, 2.0]}
    d["positions"][0]["pitch_urad"] = 4.0
    results = as_results(copy.deepcopy(d))
    assert results.extra == {"thermal_drift": d["thermal_drift"]}
    assert results.figures.get("error_motions") == {"roll_urad": [1.0, 2.0]}
    assert results.positions[0].number("pitch_urad") == 4.0
    assert json_bytes(results.to_dict()) == json_bytes(d)


def test_a_replaced_section_is_written_as_its_own_object(estimated):
    results = read_results(estimated["planar"])
    x = results.uncertainty.per_axis["X"]
    one_axis = dataclasses.replace(results, uncertainty=x)
    assert isinstance(one_axis.uncertainty, Uncertainty) and one_axis.to_dict()["uncertainty"] is x.raw
    assert as_results(results) is results  # typed once: no second read
