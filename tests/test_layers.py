"""The layer rules of SPEC section 8, enforced on every module's imports."""
from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "lps_gui"
QT_MODULES = ("PySide6", "pyqtgraph", "shiboken6")
QT_ALLOWED = ("gui", "report")
ARCHITECTURE = PACKAGE.parent / "docs" / "ARCHITECTURE.md"
MAX_CORE_ENTRIES = 12


def house(doc: Path = ARCHITECTURE) -> dict[str, str]:
    """The folders of docs/ARCHITECTURE.md's house block, "core/geometry" -> its line (layer tag and words)."""
    text = doc.read_text()
    block = text.split("## The house", 1)[1].split("```", 2)[1]
    folders: dict[str, str] = {}
    stack: list[str] = []
    for line in block.splitlines():
        m = re.match(r"^( *)(\S+)/\s+(.*)$", line)
        if not m:
            continue
        depth = len(m.group(1)) // 2
        stack[depth:] = [m.group(2)]
        folders["/".join(stack[1:])] = m.group(3)
    return folders


def layers_of(folders: dict[str, str]) -> dict[str, int]:
    """The layer of each top-level folder, from its ``[n]`` tag."""
    out = {}
    for path, words in folders.items():
        tag = re.match(r"\[(\d)\]", words)
        if tag and "/" not in path and path:
            out[path] = int(tag.group(1))
    return out


LAYER = layers_of(house())
# sideways imports allowed within layer 2: the simulated rig drives the capture engine; pipeline runs
# capture, simulation and report (the demo); the report draws truth through the one truth reduction
SIBLINGS = {("pipeline", "capture"), ("pipeline", "report"), ("pipeline", "sim"), ("sim", "capture"), ("report", "sim")}


def imports_of(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append(node.module)
    return out


def modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        yield (rel.parts[0] if len(rel.parts) > 1 else None), path


@pytest.mark.parametrize("layer,path", list(modules()), ids=lambda v: str(v) if isinstance(v, str) else None)
def test_imports_respect_layers(layer, path):
    for name in imports_of(path):
        top = name.split(".")[0]
        if top in QT_MODULES:
            assert layer in QT_ALLOWED, f"{path}: Qt ({name}) outside lps_gui/gui and lps_gui/report"
        if top == "serial":
            assert layer in ("hardware", "cli", "gui"), f"{path}: pyserial outside lps_gui/hardware"
        if name.startswith("lps_gui.") and layer in LAYER:
            target = name.split(".")[1]
            if target in LAYER:
                assert not (LAYER[target] > LAYER[layer]), f"{path}: {layer} imports the upper layer {target} ({name})"
                if LAYER[target] == LAYER[layer] and target != layer:
                    assert (layer, target) in SIBLINGS, (
                        f"{path}: {layer} imports the sibling layer {target}"
                    )


def test_everything_but_gui_imports_without_qt():
    """Design card: only lps_gui/gui may need Qt at import time (report imports it lazily)."""
    code = (
        "import sys, importlib, pkgutil, lps_gui\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('PySide6','pyqtgraph','shiboken6'): raise ImportError('Qt blocked: '+name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "for m in pkgutil.walk_packages(lps_gui.__path__, 'lps_gui.'):\n"
        "    if m.name.startswith('lps_gui.gui'): continue\n"
        "    importlib.import_module(m.name)\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=PACKAGE.parent)
    assert out.returncode == 0 and "ok" in out.stdout, out.stderr


STRING_IMPORTS = ("import_module", "__import__", "find_spec", "import_string")


@pytest.mark.parametrize("layer,path", list(modules()), ids=lambda v: str(v) if isinstance(v, str) else None)
def test_no_string_imports(layer, path):
    """Every import is an import statement, so the rules above see it (a string import would hide a layer breach)."""
    tree = ast.parse(path.read_text(), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
            assert name not in STRING_IMPORTS, f"{path}:{node.lineno}: {name}() imports by string; use an import statement"


def test_the_rules_catch_a_breach(tmp_path):
    """The checks above can fail: a core module importing the sim layer, and a string import."""
    bad = tmp_path / "bad.py"
    bad.write_text("import importlib\nfrom lps_gui.sim.truth import reduce_truth\nimportlib.import_module('lps_gui.gui')\n")
    with pytest.raises(AssertionError, match="upper layer sim"):
        test_imports_respect_layers("core", bad)
    with pytest.raises(AssertionError, match="imports by string"):
        test_no_string_imports("core", bad)
    with pytest.raises(AssertionError, match="upper layer sim"):
        test_imports_respect_layers("hardware", bad)


def module_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Which package modules each module imports, anywhere in it (inside functions too); a package's
    ``__init__`` is a node only where a module imports the package itself."""
    names = {".".join(p.relative_to(package.parent).with_suffix("").parts).removesuffix(".__init__"): p
             for p in package.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in names}
    for m, path in names.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                graph[m].update(a.name for a in node.names if a.name in names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                subs = {f"{node.module}.{a.name}" for a in node.names} & names.keys()
                graph[m].update(subs or ({node.module} & names.keys()))
    return graph


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iteratively)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_no_import_circles():
    """No two modules import each other, directly or around a circle, not even held apart by an import
    inside a function (the planar twins once were: report/figures/plots <-> report/planar_figures)."""
    assert import_circles(module_graph()) == []
    assert import_circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def package_folders(package: Path = PACKAGE) -> set[str]:
    return {str(d.relative_to(package)) for d in package.rglob("*") if d.is_dir() and any(d.glob("*.py"))
            and "__pycache__" not in d.parts}


def test_the_house_block_lists_every_folder_and_only_those():
    documented = set(house()) - {""}
    assert documented == package_folders(), (
        f"docs/ARCHITECTURE.md's house block is out of date: missing {sorted(package_folders() - documented)}, "
        f"gone {sorted(documented - package_folders())}")
    assert LAYER == {"core": 0, "io": 1, "hardware": 1, "camera": 1, "capture": 2, "sim": 2, "pipeline": 2,
                     "report": 2, "gui": 3, "cli": 3}


def test_core_is_grouped_by_concept():
    entries = [p for p in (PACKAGE / "core").iterdir() if p.name != "__pycache__" and p.name != "__init__.py"
               and (p.suffix == ".py" or p.is_dir())]
    assert len(entries) <= MAX_CORE_ENTRIES, sorted(p.name for p in entries)


@pytest.mark.parametrize("folder", sorted(package_folders()))
def test_every_package_says_what_lives_there(folder):
    init = PACKAGE / folder / "__init__.py"
    assert init.exists(), f"{init}: a package folder without __init__.py"
    doc = ast.get_docstring(ast.parse(init.read_text()))
    assert doc, f"{init}: no docstring saying what lives in {folder}/"


def test_the_house_reader_sees_a_missing_folder(tmp_path):
    doc = tmp_path / "A.md"
    doc.write_text("## The house\n\n```\nlps_gui/   [-] x\n  core/   [0] math\n    geometry/   g\n```\n")
    assert house(doc) == {"": "[-] x", "core": "[0] math", "core/geometry": "g"}
    assert layers_of(house(doc)) == {"core": 0}


REPORT_WRITERS = ("lps_gui.pipeline.demos", "lps_gui.pipeline.live", "lps_gui.pipeline.lightfield")
REPORT_READS: dict[str, set[str]] = {}  # known reads of the report by the pipeline: none


def reachable(graph: dict[str, set[str]], root: str) -> set[str]:
    """Every module ``root`` imports, directly or through others (inside functions too)."""
    seen, todo = set(), [root]
    while todo:
        for m in graph.get(todo.pop(), ()):
            if m not in seen:
                seen.add(m)
                todo.append(m)
    return seen


def test_results_are_computed_without_the_report():
    """pipeline may import report only to write a PDF (the demo, a live run, the light-field check): the path
    from a session to results.json (pipeline/estimate, pipeline/results) reaches no report module, so the
    numbers the report prints never come from the report (the verdict rows are core.metrology.verdict)."""
    graph = module_graph()
    builders = [m for m in graph if m == "lps_gui.pipeline.estimate" or m.startswith("lps_gui.pipeline.results")]
    assert len(builders) > 5
    for m in builders:
        found = sorted(r for r in reachable(graph, m) if r.startswith("lps_gui.report"))
        assert not found, f"{m} reaches the report: {found}"
    for m in graph:
        if m.startswith("lps_gui.pipeline") and not m.startswith(REPORT_WRITERS):
            found = sorted(r for r in graph[m] - REPORT_READS.get(m, set()) if r.startswith("lps_gui.report"))
            assert not found, f"{m} imports the report to compute something: {found}"
    assert reachable({"a": {"b"}, "b": {"c"}, "c": set()}, "a") == {"b", "c"}
