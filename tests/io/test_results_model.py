"""results.json read once into typed sections: nothing lost, one-line errors naming the field, new sections kept."""
from __future__ import annotations

import copy
import dataclasses
import json

import pytest

from lps_gui.cli import main as lps_main
from lps_gui.core.truth.simulate import small_spec
from lps_gui.errors import InputError
from lps_gui.io.jsonfile import json_bytes
from lps_gui.io.results.model import Results, as_results, read_results
from lps_gui.io.results.sections import Uncertainty
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


@pytest.fixture(scope="module")
def estimated(tmp_path_factory, small_planar_estimated):
    """{"line": folder, "planar": folder}: simulated point sessions estimated by the one path (a few seconds);
    the planar one is the shared session of tests/conftest.py (read only)."""
    root = tmp_path_factory.mktemp("results-model")
    simulate_point_session(small_spec(seed=3, views=12, directions="both", runs=2), root / "line")
    estimate_session(root / "line")
    return {"line": root / "line", "planar": small_planar_estimated}


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
    from lps_gui.pipeline.demos.run import run_demo

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


@pytest.fixture(scope="module")
def sections(tmp_path_factory, min_step_demo, settling_demo):
    """{kind: folder} of sessions whose results carry the newer sections: a row of targets with a tool point
    (targets, error_motions and its tool point, truth_comparison.targets), a planar constellation (both axes' error
    motions, (x, y) stretches), the ASME min-step and settling tests; simulated points, estimated by the one path
    (seconds). The ASME tests are the run's own `lps demo --test` sessions (tests/conftest.py; read only)."""
    root = tmp_path_factory.mktemp("results-sections")
    assert lps_main(["simulate", str(root / "row"), "--points", "--preset", "small-row", "--seed", "2"]) == 0
    meta_path = root / "row" / "session.json"
    meta = json.loads(meta_path.read_text())
    meta["tool_point"] = {"offset_mm": [0.0, 40.0, -25.0], "frame": "stage"}
    meta_path.write_text(json.dumps(meta, indent=2))
    from lps_gui.core.planning.plan import Plan
    from lps_gui.core.planning.target_presets import paper_constellation_spec

    plan = Plan.xy(start_mm=(0.0, 0.0), stop_mm=(1524.0, 1016.0), step_mm=(254.0, 254.0))
    simulate_point_session(paper_constellation_spec(seed=0, plan=plan), root / "constellation")
    for name in ("row", "constellation"):
        estimate_session(root / name)
    return {"row": root / "row", "constellation": root / "constellation",
            "min-step": min_step_demo.session_dir, "settling": settling_demo.session_dir}


@pytest.mark.parametrize("kind", ["row", "constellation", "min-step", "settling"])
def test_the_newer_sections_round_trip_byte_for_byte(sections, kind):
    path = sections[kind] / "results.json"
    results = read_results(path)
    assert json_bytes(results.to_dict()) == path.read_bytes()
    assert results.extra == {}  # targets, error_motions, asme_b5_64: typed, not unknown extras
    d = _document(sections[kind])
    if kind in ("row", "constellation"):
        assert [t.id for t in results.targets] == [t["id"] for t in d["targets"]]
        last, first = results.targets[-1], d["targets"][-1]
        assert last.p_sigma_mm == tuple(first["p_sigma_mm"]) and last.seen_by == tuple(first["seen_by"])
        assert last.stretch == tuple(tuple(end) for end in first["stretch_mm"])
        assert len(last.stretch[0]) == (2 if kind == "constellation" else 1)
        assert last.covered_fraction == first["covered_fraction"] and last.views == first["views"]
        assert results.truth_comparison.targets.max_abs_z == d["truth_comparison"]["targets"]["max_abs_z"]
    em, raw = results.error_motions, d["error_motions"]
    assert list(em.motions) == list(raw["motions"])
    assert em.axis_names == tuple(raw.get("axes") or [raw["axis"]])
    for iso, m in em.motions.items():
        unit = raw["motions"][iso]["unit"]
        assert m.unit == unit and m.span() == raw["motions"][iso][f"span_{unit}"]
        assert m.values == tuple(raw["motions"][iso]["values"]) and em.is_resolved(iso) == raw["resolved"][iso]
    if kind == "row":
        assert em.tool_point.offset_mm == (0.0, 40.0, -25.0)
        assert em.tool_point.max_abs_abbe_um == raw["tool_point"]["max_abs_abbe_um"]
    if kind == "constellation":
        assert em.motions["ECY"].along == "Y" and em.motions["ECY"].positions_mm == tuple(
            raw["motions"]["ECY"]["positions_mm"])
    asme = results.asme_b5_64  # line sessions only
    assert (asme is not None) == (kind != "constellation")
    assert (asme is not None and asme.has_test) == (kind in ("min-step", "settling"))
    if kind == "min-step":
        step, rs = asme.incremental_step, d["asme_b5_64"]["incremental_step"]
        assert step.sticks == rs["sticks"] and step.truth.dead_band_um == 3.0
        assert [s.achieved_um for s in step.steps] == [s["achieved_um"] for s in rs["steps"]]
        assert step.sizes[0].n_stuck_by_noise == rs["sizes"][0]["n_stuck_by_noise"]
    if kind == "settling":
        settling, rs = asme.settling, d["asme_b5_64"]["settling"]
        assert settling.settling_time_s == rs["settling_time_s"] and len(settling.stops) == rs["n_stops"]
        assert settling.stops[0].position_um == tuple(rs["stops"][0]["position_um"])
        assert settling.stops[0].sigmas == rs["stops"][0]["sigmas"]
        assert "Settling time" in [r.figure for r in asme.test_uncertainty_ratio]


def test_a_wrong_value_in_a_newer_section_names_its_field(sections):
    d = _document(sections["row"])
    d["targets"][1]["p_sigma_mm"][2] = "small"
    with pytest.raises(InputError, match=r"'targets\[1\]\.p_sigma_mm\[2\]'"):
        Results.from_dict(d, source="r.json")
    d = _document(sections["row"])
    d["error_motions"]["motions"]["EAX"]["values"] = 3.0
    with pytest.raises(InputError, match=r"'error_motions\.motions\.EAX\.values'"):
        Results.from_dict(d, source="r.json")


def _sections_of(d: dict) -> list[tuple[type, dict]]:
    """(section class, its JSON object) of every section a builder writes through :meth:`Section.of`, and more."""
    from lps_gui.io.results import sections as S

    figures = d.get("figures") or {}
    out = [(S.Parameters, d["parameters"]), (S.EnvironmentRecord, d["environment"]), (S.Uncertainty, d["uncertainty"]),
           (S.Figures, figures), (S.TruthComparison, d["truth_comparison"])]
    out += [(S.Position, row) for row in d["positions"]] + [(S.Flag, f) for f in d.get("flags") or []]
    out += [(S.BudgetRow, b) for b in (d["uncertainty"].get("budget") or [])]
    if figures.get("single_run"):
        out += [(S.SingleRun, figures["single_run"]), (S.Iso230, figures["iso230_2"])]
    out += [(section, d[key]) for section, key in ((S.AsmeB564, "asme_b5_64"), (S.ErrorMotions, "error_motions"))
            if d.get(key)]
    return out + [(S.TargetRecord, row) for row in d.get("targets") or []]


@pytest.mark.parametrize("kind", ["line", "planar"])
def test_each_section_is_written_and_read_through_one_definition(estimated, kind):
    d = _document(estimated[kind])
    for section, obj in _sections_of(d):
        read = section.from_dict(obj)
        assert read.to_dict() == obj, section.__name__  # to_dict of a read section is the JSON
        built = section.of(**obj)
        assert section.from_dict(built.to_dict()) == built == read, section.__name__
        assert json.dumps(built.to_dict()) == json.dumps(obj), section.__name__  # the keys in the file's order


def test_a_builder_cannot_write_a_field_the_readers_do_not_know():
    from lps_gui.io.results.sections import EnvironmentRecord, Flag, Iso230, SingleRun, Uncertainty

    assert Flag.of(index=None, kind="lens_model", message="m").to_dict() == {"index": None, "kind": "lens_model",
                                                                              "message": "m"}
    for section, field in ((Flag, "kindd"), (SingleRun, "scale_pm"), (Uncertainty, "figures_k3"),
                           (EnvironmentRecord, "board_temperature")):
        with pytest.raises(TypeError, match=field):
            section.of(**{field: 1.0})
    with pytest.raises(InputError, match="scale_ppm"):  # a field of the wrong type: the reader's own message
        SingleRun.of(scale_ppm="large")
    assert Iso230.of(A_um=3.0).get("A_um") == 3.0  # E/M/B/R/A by name: an open set
    nested = Uncertainty.of(per_axis={"X": Uncertainty.of(expanded_k2_um=2.0)})
    assert nested.per_axis["X"].expanded_k2_um == 2.0 and nested.to_dict() == {"per_axis": {"X": {"expanded_k2_um": 2.0}}}


def test_results_sections_have_one_order_whatever_order_a_builder_writes_them():
    """Issue 34: a builder writes a section where it is made; its place in results.json is SECTIONS' (no builder
    reads the document's keys back to keep an order); a section not named there is refused, not placed anywhere."""
    from lps_gui.io.results.document import SECTIONS, in_section_order

    written = {"verdict": 1, "targets": 2, "format": 3, "summary": 4, "board": 5}
    ordered = in_section_order(written)
    assert list(ordered) == ["format", "board", "targets", "summary", "verdict"]
    assert list(ordered) == [k for k in SECTIONS if k in written] and next(iter(written)) == "verdict"
    with pytest.raises(ValueError, match="lightfield"):
        in_section_order({"format": 1, "lightfield": 2})
