"""A protocol's package is imported by its own files and the registry only (issue 36).

The simulated stage, the line emulator, capture, GUI and the other protocols
speak no protocol: before issue 36 the simulated stage imported GRBL's codes
and Marlin's emulator subclassed GRBL's. ``lps emulate-grbl`` (cli/emulate_grbl.py)
is GRBL's own command and builds GRBL's fault switches.
"""
from __future__ import annotations

import ast
from pathlib import Path

import lps_gui

ROOT = Path(lps_gui.__file__).parent
PROTOCOLS = {  # protocol module prefix -> files outside it allowed to import it
    "lps_gui.hardware.grbl": {"hardware/registry.py", "cli/emulate_grbl.py"},
    "lps_gui.hardware.marlin": {"hardware/registry.py"},
    "lps_gui.hardware.zaber": {"hardware/registry.py"},
    "lps_gui.hardware.thorlabs": {"hardware/registry.py"},
}


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_only_the_registry_imports_a_protocol():
    leaks = []
    for path in sorted(ROOT.rglob("*.py")):  # parsed once for every protocol
        rel = path.relative_to(ROOT).as_posix()
        modules = _imports(path)
        for prefix, allowed in PROTOCOLS.items():
            own = prefix.removeprefix("lps_gui.").replace(".", "/")
            if rel.startswith(own) or rel in allowed:  # its package (grbl/), its module and emulator (zaber*.py)
                continue
            hits = sorted(m for m in modules if m == prefix or m.startswith((prefix + ".", prefix + "_")))
            if hits:
                leaks.append(f"{rel}: {', '.join(hits)}")
    assert not leaks, leaks
