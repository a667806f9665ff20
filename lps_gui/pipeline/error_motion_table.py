"""`lps compensate --error-motions FILE`: the axis's six error motions per nominal position, as a CSV table.

No controller of ours takes angular tables (LinuxCNC, Mach4, Klipper, Marlin and
RepRapFirmware compensate positions, backlash, skew and bed height, not
roll, pitch or yaw: docs/error-motions.md), so the table is for the user's own
compensation (a CNC with volumetric compensation, a robot's calibration) or
records: per target, the mean over every capture of each motion of results.json
``error_motions`` and the sigma of that mean, without the reference stop's own
noise (the centred sigma; with several runs the run-to-run scatter when larger).
A motion the data do not resolve (core/metrology/resolution) has empty cells.
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from lps_gui.core.metrology.compensation import target_means
from lps_gui.errors import InputError
from lps_gui.io.atomic import write_bytes_atomic
from lps_gui.io.results.model import Results, as_results

UNIT_SUFFIX = {"um": "um", "urad": "urad"}


def error_motion_table(results: Results | Mapping[str, Any]) -> tuple[list[str], list[list[str]]]:
    """(header, rows): ``nominal_mm`` then, per motion, ``<iso>_<unit>`` and ``<iso>_sigma_<unit>``."""
    results = as_results(results)
    section = results.error_motions
    if section is None or not section.motions:
        raise InputError("results.json has no error_motions; estimate the session again with this version "
                         "(lps estimate SESSION)")
    target = results.column("target_mm")
    header, columns = ["nominal_mm"], []
    nominal = None
    for iso, m in section.motions.items():
        unit = UNIT_SUFFIX[m.unit]
        header += [f"{iso.lower()}_{unit}", f"{iso.lower()}_sigma_{unit}"]
        v = np.array(m.values, dtype=float)
        s = np.array(m.centred_sigma, dtype=float)
        ok = np.isfinite(v) & np.isfinite(s)
        t, mean, sigma = target_means(target[ok], v[ok], s[ok], np.zeros(int(ok.sum())))
        nominal = t if nominal is None else nominal
        if not section.is_resolved(iso) or len(t) != len(nominal):
            mean = sigma = np.full(len(nominal), np.nan)
        columns += [mean, sigma]
    body = [[f"{nominal[i]:.6f}"] + ["" if not np.isfinite(c[i]) else f"{c[i]:.4f}" for c in columns]
            for i in range(len(nominal))]
    return header, body


def write_error_motion_table(path: Path | str, results: Results | Mapping[str, Any]) -> Path:
    header, body = error_motion_table(results)
    text = ",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in body)
    path = Path(path)
    write_bytes_atomic(path, text.encode())
    return path
