"""The estimation methods are named once (core/estimator/methods.py): the CLI, the GUI and the report read them."""
from __future__ import annotations

import ast
from pathlib import Path

from lps_gui.cli import build_parser
from lps_gui.core.estimator import methods
from lps_gui.core.estimator.estimate_types import EstimateOptions
from lps_gui.report.pages.summary import method_rows
from tests.report.conftest import make_results

PACKAGE = Path(__file__).resolve().parents[2] / "lps_gui"


def test_the_cli_offers_exactly_the_registry():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices["estimate"]
    method = next(a for a in sub._actions if a.dest == "method")
    assert tuple(method.choices) == methods.METHODS and method.default == methods.DEFAULT


def test_methods_by_axes_come_from_the_registry():
    assert methods.METHODS_BY_AXES[1] == ("joint", "hybrid", "pnp", "calibrate")
    assert methods.METHODS_BY_AXES[2] == ("joint", "pnp")
    for name in methods.METHODS:
        EstimateOptions(method=name)  # every registered name is accepted by the options


def test_the_report_words_every_method_from_the_registry():
    results, _ = make_results(views=6)
    for m in methods.REGISTRY:
        assert method_rows({**results, "method": m.name})[0] == ("Method", m.report_text)


def test_no_other_module_lists_the_method_names():
    """A tuple or set literal holding two or more method names outside the registry is a second list."""
    names = set(methods.METHODS)
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        if path.name == "methods.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
                found = {e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in names}
                if len(found) >= 2:
                    offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert offenders == []
