"""The ISO 230-2 per-target table, as a laser calibration report prints it.

Per target P_j: mean deviation each way, standard deviation s each way
(over the runs, ddof 1), unidirectional repeatability R = 4 s each way,
reversal B_j, bidirectional repeatability R_j and the mean bidirectional
deviation. Values come from results.json ``figures.iso230_2.per_target``
(:class:`lps_gui.core.metrology.iso230.TargetTable`). No Qt here.
"""
from __future__ import annotations

from typing import Any

from lps_gui.io.results.model import Results, as_results
from lps_gui.report.pages.summary import DASH, _num

UM = "\u00b5m"
# (key of per_target or a derived name, header, width mm)
COLUMNS = (("target_mm", "P\u2c7c\n[mm]", 16), ("n", "runs\n\u2191/\u2193", 12),
           ("mean_up_um", f"x\u0304 \u2191\n[{UM}]", 16), ("mean_down_um", f"x\u0304 \u2193\n[{UM}]", 16),
           ("std_up_um", f"s \u2191\n[{UM}]", 14), ("std_down_um", f"s \u2193\n[{UM}]", 14),
           ("R_up_um", f"R \u2191 = 4s\n[{UM}]", 18), ("R_down_um", f"R \u2193 = 4s\n[{UM}]", 18),
           ("reversal_um", f"B\u2c7c\n[{UM}]", 14), ("R_um", f"R\u2c7c\n[{UM}]", 14),
           ("mean_bi_um", f"(x\u0304\u2191+x\u0304\u2193)/2\n[{UM}]", 24))


def iso_target_table(results: Results | dict[str, Any]) -> tuple[list[str], list[list[str]], list[float]] | None:
    """Header, rows and widths (mm) of the per-target table; None when the results have no ISO figures."""
    iso = as_results(results).figures.iso230_2
    tab = iso.per_target if iso is not None else None
    targets = tab.get("target_mm") if tab else None
    if not targets:
        return None
    rows = []
    for j, t in enumerate(targets):
        def get(key: str) -> float | None:
            values = tab.get(key) or []
            return _num(values[j]) if j < len(values) else None

        up, down = get("mean_up_um"), get("mean_down_um")
        cells = []
        for key, _, _ in COLUMNS:
            if key == "target_mm":
                cells.append(f"{float(t):.3f}")
            elif key == "n":
                cells.append(f"{int(get('n_up') or 0)}/{int(get('n_down') or 0)}")
            elif key == "mean_bi_um":
                cells.append(DASH if up is None or down is None else f"{(up + down) / 2:.2f}")
            else:
                v = get(key)
                cells.append(DASH if v is None else f"{v:.2f}")
        rows.append(cells)
    return [c[1] for c in COLUMNS], rows, [float(c[2]) for c in COLUMNS]
