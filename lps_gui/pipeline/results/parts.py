"""What an axis's builder (a line's, a plane's) makes: its document so far and the values the later builders take.

Why: the sections added after the axis's own (targets, error motions, the budget, the ASME test, the verdict,
the truth self-check) are computed from these values as passed down, never by reading back the document they
are being written into (:func:`lps_gui.pipeline.estimate.build_results` holds them and writes each once).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class AxisResults:
    """One axis builder's output: ``document`` in schema order (written, never read by a later builder) and the
    values its sections hold, as JSON data (the same objects the document holds)."""

    document: dict[str, Any]
    parameters: dict[str, Any]
    board: dict[str, Any]
    positions: list[dict[str, Any]]
    figures: dict[str, Any]
    flags: list[dict[str, Any]]
    truth_comparison: dict[str, Any] | None  # a plane's; a line's is made after the error motions (build_results)
