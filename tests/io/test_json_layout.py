"""json_bytes lays JSON out with the C encoder (rows on one line); the values read back are exactly those
of json.dumps(indent=2), the layout it replaced (issue 15)."""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from lps_gui.core.truth.simulate import small_spec
from lps_gui.io.jsonfile import _default, json_bytes
from lps_gui.pipeline.estimate import estimate_session
from lps_gui.sim.points import simulate_point_session


def _previous(data) -> bytes:
    return (json.dumps(data, indent=2, sort_keys=False, default=_default) + "\n").encode("utf-8")


def _loads(text):
    """Parsed with NaN / Infinity kept as their words, so that == compares them too."""
    return json.loads(text, parse_constant=lambda word: word)


def test_results_json_of_a_session_reads_back_as_with_the_indented_encoder(tmp_path):
    spec = replace(small_spec(seed=3, views=12, directions="both", runs=2), replaced_views=(4,), missing_fraction=0.02)
    simulate_point_session(spec, tmp_path / "s")
    results = estimate_session(tmp_path / "s")
    written = (tmp_path / "s" / "results.json").read_bytes()
    assert _loads(written) == _loads(_previous(results))
    assert list(_loads(written)) == list(results)  # key order kept
    lines = written.decode().splitlines()
    assert lines[1] == '  "format": "lps-results/1",'  # the top level stays indented, one key per line
    start = lines.index('  "positions": [') + 1
    rows = lines[start:lines.index("  ],", start)]
    assert len(rows) == len(results["positions"])  # one line per position
    assert [json.loads(row.rstrip(",")) for row in rows] == json.loads(json.dumps(results["positions"]))


def test_numpy_values_keys_and_special_floats_as_before():
    doc = {"a": np.arange(6.0).reshape(2, 3), "b": np.float64(1.5), "c": np.int64(3), "d": [np.int64(1), 2.0, None, True],
           "e": {}, "f": [], "g": [[], {}], 1: "int key", 2.5: "float key", None: "none", "h": (1, 2), "i": Path("/x"),
           "j": np.bool_(True), "k": [float("nan"), float("inf"), -float("inf"), -0.0, 1e-300, 0.1 + 0.2],
           "l": "\u00b5m \"q\"\n", "m": [{"x": np.array([1, 2])}, [1, [2, {"y": 3}]]], "n": np.array([]),
           "o": np.float32(0.1), "p": [np.array([1.0])], "q": {"r": {"s": [{"t": []}]}}}
    new, old = json_bytes(doc), _previous(doc)
    assert _loads(new) == _loads(old) and list(_loads(new)) == list(_loads(old))
    for value in ([], {}, 1.0, "x", None, [[1]], [1, 2]):
        assert json.loads(json_bytes(value)) == value
