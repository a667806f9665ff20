"""Issue 34, builders return values: the planar builder writes the simulator's error at each grid node into new
nodes, made from the true deviations passed in, and leaves the nodes of the figures it was given as they were."""
from __future__ import annotations

from dataclasses import replace
from types import MappingProxyType

import numpy as np


def test_planar_truth_nodes_are_new_and_match_the_true_deviations(small_planar_estimated, monkeypatch):
    from lps_gui.pipeline import estimate as pipeline
    from lps_gui.pipeline.results import planar as builder
    from lps_gui.pipeline.session_input import read_session_input

    given = {}

    def read_only_nodes(*args, **kwargs):
        figs = builder_planar_figures(*args, **kwargs)
        given["nodes"] = [dict(n) for n in figs.nodes]
        return replace(figs, nodes=[MappingProxyType(n) for n in figs.nodes])  # a write to them raises

    builder_planar_figures = builder.planar_figures
    monkeypatch.setattr(builder, "planar_figures", read_only_nodes)
    inp = read_session_input(small_planar_estimated, None)
    obs = pipeline.observations_from_session(inp)
    est = pipeline.estimate_with_self_calibration(obs, pipeline.make_options("joint"))
    part = builder.build_planar_results(inp, obs, est, "session.json")
    nodes = part.figures["planar"]["nodes"]
    assert [{k: n[k] for k in g} for n, g in zip(nodes, given["nodes"])] == given["nodes"]
    assert all("truth_error_um" not in g for g in given["nodes"])
    # each node's truth error is the mean true deviation (simulator) of the used captures at that node
    rows = part.positions
    target = np.array([[r["target_x_mm"], r["target_y_mm"]] for r in rows])
    true = np.array([[np.nan if r.get(k) is None else r[k] for k in ("truth_deviation_x_um", "truth_deviation_y_um")]
                     for r in rows])
    used = np.array([r["used"] and r["deviation_x_um"] is not None for r in rows]) & np.isfinite(true).all(axis=1)
    checked = 0
    for n in nodes:
        at = used & np.all(np.abs(target - n["target_mm"]) < 1e-6, axis=1)
        if at.any():
            np.testing.assert_allclose(n["truth_error_um"], true[at].mean(axis=0), rtol=0, atol=1e-9)
            checked += 1
    assert checked >= 4
    assert all(r.get("out_of_plane_um") is not None for r in rows if r["used"])  # built into the rows, joint method
