"""The names of results.json's position columns, written once: builders, readers, report and GUI import them.

A column is renamed here and nowhere else (issue 34: a literal such as the
deviation's key was spread over a dozen modules). The CSV column orders are
:data:`POSITION_COLUMNS` and :data:`PLANAR_POSITION_COLUMNS`.
"""
from __future__ import annotations

INDEX = "index"
RUN = "run"
DIRECTION = "direction"
TARGET_MM = "target_mm"
MEASURED_MM = "measured_mm"
DEVIATION_UM = "deviation_um"  # measured minus commanded position, um (SPEC 5)
SIGMA_UM = "sigma_um"
SIGMA_TOTAL_UM = "sigma_total_um"
STEP_SIGMA_UM = "step_sigma_um"
RMS_PX = "rms_px"
N_CORNERS = "n_corners"
OUTLIER = "outlier"
OUTLIER_REASON = "outlier_reason"
USED = "used"
FILE = "file"

POSITION_COLUMNS = (INDEX, RUN, DIRECTION, TARGET_MM, MEASURED_MM, DEVIATION_UM, SIGMA_UM, RMS_PX, OUTLIER,
                    "straightness_um_1", "straightness_um_2", "roll_urad", "pitch_urad", "yaw_urad")
PLANAR_POSITION_COLUMNS = (  # SPEC 10
    INDEX, RUN, DIRECTION, "target_x_mm", "target_y_mm", "measured_x_mm", "measured_y_mm", "deviation_x_um",
    "deviation_y_um", "sigma_x_um", "sigma_y_um", RMS_PX, OUTLIER)
