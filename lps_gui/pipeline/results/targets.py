"""The targets section of results.json (SPEC 13): each target's pose, its sigma, who saw and tied it.

``stretch_mm`` is the part of the travel over which a target was seen: a
printed scale error of that target enters only the positions measured there,
so the uncertainty budget takes each target's scale term over its stretch.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from lps_gui.core.geometry.rotation import log_so3
from lps_gui.core.geometry.targets import Target, target_offsets

MIN_CORNERS = 6  # a view "saw" a target when it has at least this many of its corners


def target_rows(targets: list[Target], Q: np.ndarray, p: np.ndarray, sigma: np.ndarray, corners_px: np.ndarray,
                targets_mm: np.ndarray, used: np.ndarray) -> list[dict[str, Any]]:
    """One dict per target: id, rvec_rad, rvec_sigma_rad, p_mm, p_sigma_mm, views, ties, stretch_mm."""
    offsets = target_offsets(targets)
    seen = np.stack([np.isfinite(corners_px[:, offsets[j]: offsets[j + 1], 0]).sum(axis=1) >= MIN_CORNERS
                     for j in range(len(targets))], axis=1) & np.asarray(used, bool)[:, None]
    several = seen.sum(axis=1) >= 2
    x = np.asarray(targets_mm, float).reshape(len(corners_px), -1)
    rows = []
    for j, t in enumerate(targets):
        views = seen[:, j]
        stretch = [[float(v) for v in x[views].min(axis=0)], [float(v) for v in x[views].max(axis=0)]] if views.any() else None
        rows.append({
            "id": t.id, "first_marker": t.first_marker,
            "rvec_rad": [float(v) for v in log_so3(Q[j])], "rvec_sigma_rad": [float(v) for v in sigma[j, 0:3]],
            "p_mm": [float(v) for v in p[j]], "p_sigma_mm": [float(v) for v in sigma[j, 3:6]],
            "views": int(views.sum()), "ties": int((views & several).sum()), "stretch_mm": stretch,
        })
    return rows
