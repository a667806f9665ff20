"""positions.csv written column by column is byte for byte what csv.writer wrote row by row (quoting included)."""
import csv
import io

import numpy as np
import pytest

from lps_gui.io.results import document as rf


def _row_by_row(results):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    columns = rf.position_columns(results)
    w.writerow(columns)
    for row in results["positions"]:
        w.writerow([rf._fmt(row.get(c)) for c in columns])
    return buf.getvalue()


ROW = {"index": 1, "run": np.int64(2), "direction": "+", "target_mm": np.float64(1.5), "measured_mm": float("nan"),
       "deviation_um": None, "sigma_um": True, "rms_px": 0.123456789, "outlier": False, "straightness_um_1": 1e-300,
       "straightness_um_2": float("inf"), "roll_urad": -0.0, "pitch_urad": 12345678.9, "yaw_urad": np.float32(0.1)}


@pytest.mark.parametrize("odd", [None, 'a,"b"', "x\ny", "plain"])
def test_same_bytes_as_the_csv_module(odd):
    rows = [dict(ROW), {"index": 2}, dict(ROW, index=3, direction="-")]
    if odd is not None:
        rows[0]["rms_px"] = odd
    results = {"positions": rows}
    assert rf.positions_csv(results) == _row_by_row(results)
    planar = {"axes": ["X", "Y"], "positions": [{"index": 0, "target_x_mm": 1.0, "sigma_y_um": odd}]}
    assert rf.positions_csv(planar) == _row_by_row(planar)
