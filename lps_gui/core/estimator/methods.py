"""The estimation methods, named once: what the CLI offers, the GUI lists and the report prints.

A light module (no numpy) so that ``lps estimate --help`` stays instant. A
new method is one :class:`Method` row here and its solver in
:mod:`lps_gui.core.estimator.estimate`.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Method:
    """One estimation method: its key in results.json, the labels people read, the axes it handles."""

    name: str
    label: str  # the GUI's combo
    report_text: str  # the report's "Method" row
    axes: tuple[int, ...]  # 1: a line, 2: a plane
    in_gui: bool = True  # the full calibration is a reference for experts: CLI only
    per_view: bool = False  # solved view by view (core/estimator/per_view.py), not by the joint model


REGISTRY: tuple[Method, ...] = (
    Method("joint", "Joint LM (all positions at once)",
           "joint LM (all positions, orientation and line at once)", (1, 2)),
    Method("hybrid", "Hybrid (paper: PnP + LM + grid search)",
           "paper's hybrid algorithm (LM + per-view grid search)", (1,)),  # the grid search is 1-D by construction
    Method("pnp", "Per-view PnP", "per-view PnP (baseline)", (1, 2), per_view=True),
    Method("calibrate", "Full calibration (reference)", "full calibration (reference only)", (1,), in_gui=False,
           per_view=True),
)
DEFAULT = "joint"
METHODS: tuple[str, ...] = tuple(m.name for m in REGISTRY)
METHODS_BY_AXES: dict[int, tuple[str, ...]] = {d: tuple(m.name for m in REGISTRY if d in m.axes) for d in (1, 2)}
BY_NAME: dict[str, Method] = {m.name: m for m in REGISTRY}


def report_text(name: str) -> str:
    """The report's wording of a method (the key itself for a method this version does not know)."""
    return BY_NAME[name].report_text if name in BY_NAME else name
