"""Measurement environment (session.json ``environment``) and the board's thermal scale.

ISO 1 fixes 20 C as the reference temperature of lengths. The board's square
size is given at 20 C; a board at temperature T with expansion coefficient
alpha has squares longer by the factor ``1 + alpha (T - 20)``. The estimator
measures every length in units of the square, so positions measured with
the nominal square are too short by that factor; :func:`thermal_scale`
returns the factor by which the square (and so every length) is corrected:
23 C and 23 ppm/K give +69 ppm. The stage's own expansion is not corrected
(the stage is measured as it is); its temperature enters the uncertainty
budget (:mod:`lps_gui.core.metrology.uncertainty_budget`). Pure math, no I/O.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

from lps_gui.core.geometry.board import Board
from lps_gui.errors import InputError

REFERENCE_TEMPERATURE_C = 20.0  # ISO 1
DEFAULT_TEMPERATURE_U_K = 0.5  # standard uncertainty of a thermometer reading when none is given
DEFAULT_CTE_RELATIVE_U = 0.1  # ISO/TR 230-9: +-10 % of the expansion coefficient when none is given

FIELDS = ("board_temperature_c", "board_cte_ppm_per_k", "square_mm_uncertainty_um", "stage_temperature_c",
          "stage_cte_ppm_per_k", "temperature_uncertainty_k", "board_cte_uncertainty_ppm_per_k", "notes")


@dataclass(frozen=True)
class Environment:
    """What the operator measured around the test; None where not recorded."""

    board_temperature_c: float | None = None
    board_cte_ppm_per_k: float | None = None
    square_mm_uncertainty_um: float | None = None  # standard uncertainty of one square's size
    stage_temperature_c: float | None = None
    stage_cte_ppm_per_k: float | None = None
    temperature_uncertainty_k: float | None = None  # of each thermometer reading; default 0.5 K
    board_cte_uncertainty_ppm_per_k: float | None = None  # default 10 % of the coefficient
    notes: str = ""

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None, where: str = "environment") -> "Environment":
        """Parse session.json ``environment``; unknown keys and non-numbers are one-line errors."""
        if not d:
            return cls()
        if not isinstance(d, dict):
            raise InputError(f"{where}: must be an object with keys {', '.join(FIELDS)}")
        unknown = sorted(set(d) - set(FIELDS))
        if unknown:
            raise InputError(f"{where}: unknown key(s) {', '.join(unknown)}; use {', '.join(FIELDS)}")
        values: dict[str, Any] = {"notes": str(d.get("notes") or "")}
        for key in FIELDS[:-1]:
            v = d.get(key)
            if v is None or v == "":
                continue
            try:
                f = float(v)
            except (TypeError, ValueError):
                raise InputError(f"{where}: {key} must be a number, got {v!r}") from None
            if not math.isfinite(f):
                raise InputError(f"{where}: {key} must be finite, got {v!r}")
            if key.endswith("uncertainty_um") or key.endswith("uncertainty_k") or key.endswith("uncertainty_ppm_per_k"):
                if f < 0:
                    raise InputError(f"{where}: {key} is an uncertainty and cannot be negative, got {f}")
            if key.endswith("temperature_c") and not -50.0 <= f <= 100.0:
                raise InputError(f"{where}: {key} = {f} C is outside -50..100 C; give degrees Celsius")
            values[key] = f
        return cls(**values)

    def to_dict(self) -> dict[str, Any]:
        """JSON form without the fields that were not recorded."""
        return {k: v for k, v in asdict(self).items() if v not in (None, "")}

    @property
    def board_delta_k(self) -> float | None:
        """Board temperature minus 20 C, None when not recorded."""
        return None if self.board_temperature_c is None else self.board_temperature_c - REFERENCE_TEMPERATURE_C

    @property
    def stage_delta_k(self) -> float | None:
        return None if self.stage_temperature_c is None else self.stage_temperature_c - REFERENCE_TEMPERATURE_C

    def temperature_u_k(self) -> float:
        return DEFAULT_TEMPERATURE_U_K if self.temperature_uncertainty_k is None else self.temperature_uncertainty_k

    def board_cte_u_ppm(self) -> float:
        if self.board_cte_uncertainty_ppm_per_k is not None:
            return self.board_cte_uncertainty_ppm_per_k
        return DEFAULT_CTE_RELATIVE_U * abs(self.board_cte_ppm_per_k or 0.0)


def thermal_scale(env: Environment) -> float:
    """Factor on the nominal (20 C) square size: ``1 + alpha (T_board - 20)``; 1 when not recorded.

    Sign: a warm board has larger squares, so the true displacement is the
    measured one (in nominal squares) times this factor (> 1 above 20 C).
    """
    if env.board_delta_k is None or env.board_cte_ppm_per_k is None:
        return 1.0
    return 1.0 + 1e-6 * env.board_cte_ppm_per_k * env.board_delta_k


def corrected_board(board: Board, env: Environment) -> Board:
    """The board with its square size at the measurement temperature (the estimator's length unit)."""
    factor = thermal_scale(env)
    return board if factor == 1.0 else replace(board, square_mm=board.square_mm * factor)


def thermal_record(board: Board, env: Environment) -> dict[str, Any]:
    """What results.json ``environment`` states about the correction applied."""
    factor = thermal_scale(env)
    return {**env.to_dict(), "reference_temperature_c": REFERENCE_TEMPERATURE_C,
            "board_scale_correction_ppm": 1e6 * (factor - 1.0),
            "square_mm_nominal": board.square_mm, "square_mm_used": board.square_mm * factor}
