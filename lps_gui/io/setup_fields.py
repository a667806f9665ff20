"""session.json's set-up entries field by field: key, label (GUI), switch and help (`lps capture`).

The CLI's switches, the GUI's form and the report's signing block are built from these tables, so
a field added here is asked for by both faces and printed by the report. Plain data, no numpy:
`lps capture --help` reads it.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class EnvField:
    """One number of session.json ``environment`` (``core.metrology.environment.FIELDS``)."""

    key: str
    label: str
    flag: str
    help: str
    lo: float  # the lowest real value the GUI's spin box offers (one step below reads "not recorded")
    hi: float
    decimals: int
    unit: str


@dataclass(frozen=True)
class IdField:
    """One text of session.json ``identification``; ``signing``: printed in the report's signing block."""

    key: str
    label: str
    flag: str
    help: str
    signing: bool = False


ENV_FIELDS = (
    EnvField("board_temperature_c", "Board temperature", "--board-temp",
             "board temperature, deg C (corrects the length scale to 20 C)", -50.0, 100.0, 2, " \u00b0C"),
    EnvField("board_cte_ppm_per_k", "Board expansion", "--board-cte",
             "board expansion coefficient, ppm/K (e.g. 23 aluminium, 8 glass)", 0.0, 100.0, 2, " ppm/K"),
    EnvField("square_mm_uncertainty_um", "Square size u", "--square-u",
             "standard uncertainty of the board's square size, \u00b5m (certificate)", 0.0, 100.0, 3, " \u00b5m"),
    EnvField("stage_temperature_c", "Stage temperature", "--stage-temp", "stage temperature, deg C",
             -50.0, 100.0, 2, " \u00b0C"),
    EnvField("stage_cte_ppm_per_k", "Stage expansion", "--stage-cte",
             "stage scale expansion coefficient, ppm/K (e.g. 11.5 steel screw)", 0.0, 100.0, 2, " ppm/K"),
    EnvField("temperature_uncertainty_k", "Thermometer u", "--temp-u",
             "standard uncertainty of the thermometers, K (default 0.5)", 0.0, 10.0, 2, " K"),
)
ID_FIELDS = (  # who and where, then the signing block's (lps_gui.report.pages.signing)
    IdField("operator", "Operator", "--operator", "operator"),
    IdField("customer", "Customer", "--customer", "customer"),
    IdField("stage_model", "Stage model", "--stage-model", "stage model"),
    IdField("stage_serial", "Stage serial", "--serial", "stage serial"),
    IdField("controller_serial", "Controller serial", "--controller-serial", "controller serial"),
    IdField("location", "Location", "--location", "location"),
    IdField("lab", "Laboratory", "--lab", "laboratory performing the measurement", True),
    IdField("certificate_number", "Certificate no.", "--certificate", "this report's certificate number", True),
    IdField("board_id", "Board id", "--board-id", "the board's (target's) identifier", True),
    IdField("board_certificate", "Board certificate", "--board-cert", "the board's calibration certificate number", True),
    IdField("thermometer", "Thermometer", "--thermometer", "the thermometer's identifier", True),
    IdField("thermometer_certificate", "Thermometer cert.", "--thermometer-cert",
            "the thermometer's calibration certificate number", True),
    IdField("camera_serial", "Camera serial", "--camera-serial", "the camera's serial number", True),
    IdField("camera_certificate", "Camera certificate", "--camera-cert",
            "the camera's (or its intrinsics') certificate number", True),
    IdField("approved_by", "Approved by", "--approved-by", "who approves the report (name, function)", True),
)
SPEC_FIELDS = (("accuracy_um", "Accuracy \u00b1"), ("repeatability_um", "Repeatability \u00b1"),
               ("straightness_um", "Straight-line accuracy"))  # session.json stage_spec keys the GUI asks for
