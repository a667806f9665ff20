"""Figures of a planar session (SPEC 10): squareness, per-axis scale, ISO 230-2 per line,
straightness of each axis along the other, and the 2-D error vector at every grid node.

Squareness is the angle between the fitted +X and +Y motion directions minus
90 deg (positive: the axes open wider than square), in urad and um/m; scales
are the lengths of those directions per commanded mm minus 1, in ppm. Their
sigmas come from the full covariance of the positions (the fit's
coefficients are linear functionals of all positions, correlated through
the shared parameters). Pure math, no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.core.metrology.iso230 import figures_for_session
from lps_gui.core.metrology.iso230_noise import (
    apply_noise_correction,
    independent_sigma_um,
    noise_corrected_iso,
    noise_corrected_worst,
)
from lps_gui.core.metrology.iso230_run import JsonDataclass, target_index
from lps_gui.core.metrology.resolution import profile_span

LINE_TOL_MM = 1e-6
MIN_LINE_TARGETS = 3


@dataclass
class AxisGeometry(JsonDataclass):
    squareness_urad: float
    squareness_sigma_urad: float
    squareness_um_per_m: float
    scale_x_ppm: float
    scale_x_sigma_ppm: float
    scale_y_ppm: float
    scale_y_sigma_ppm: float


def axis_geometry(G: np.ndarray, cov_G: np.ndarray) -> AxisGeometry:
    """Squareness and per-axis scale from the fitted motion matrix G (2x2, columns +X, +Y motion).

    First-order propagation with the analytic gradient of each figure with
    respect to G.ravel() (row-major: G00, G01, G10, G11).
    """
    gx, gy = G[:, 0], G[:, 1]
    nx, ny = float(np.linalg.norm(gx)), float(np.linalg.norm(gy))
    c = gx[0] * gy[1] - gx[1] * gy[0]  # cross: sin(angle) |gx| |gy|
    d = gx @ gy  # dot: cos(angle) |gx| |gy|
    angle = float(np.arctan2(c, d))
    # gradients w.r.t. (gx0, gx1, gy0, gy1)
    dc = np.array([gy[1], -gy[0], -gx[1], gx[0]])
    dd = np.array([gy[0], gy[1], gx[0], gx[1]])
    d_angle = (d * dc - c * dd) / (c * c + d * d)
    d_sx = np.array([gx[0] / nx, gx[1] / nx, 0.0, 0.0])
    d_sy = np.array([0.0, 0.0, gy[0] / ny, gy[1] / ny])
    # reorder from (gx0, gx1, gy0, gy1) = (G00, G10, G01, G11) to row-major G.ravel()
    order = [0, 2, 1, 3]
    cov = cov_G[np.ix_(order, order)]

    def sd(g: np.ndarray) -> float:
        return float(np.sqrt(max(g @ cov @ g, 0.0)))

    sq = (angle - np.pi / 2.0) * 1e6
    return AxisGeometry(
        squareness_urad=sq, squareness_sigma_urad=sd(d_angle) * 1e6, squareness_um_per_m=float(np.tan(sq * 1e-6) * 1e6),
        scale_x_ppm=(nx - 1.0) * 1e6, scale_x_sigma_ppm=sd(d_sx) * 1e6,
        scale_y_ppm=(ny - 1.0) * 1e6, scale_y_sigma_ppm=sd(d_sy) * 1e6,
    )


@dataclass
class LineFigures(JsonDataclass):
    """One line of the plan along an axis (the other axis' target constant)."""

    axis: str  # "X" or "Y": the moving axis
    at_mm: float  # the other axis' target
    n_targets: int
    straightness_um: float | None  # peak-to-valley of the cross-axis deviation from its least-squares line
    straightness_sigma_um: float | None  # median 1-sigma of the cross-axis coordinates on the line
    iso230_2: dict[str, Any] | None  # figures of core.iso230 for the moving axis along this line
    straightness: dict[str, Any] | None = None  # core.resolution.profile_span: in the plane, with its noise p-v
    out_of_plane: dict[str, Any] | None = None  # the same for the displacement along the plane normal


@dataclass
class PlanarFigures(JsonDataclass):
    geometry: AxisGeometry
    lines: list[LineFigures]
    per_axis: dict[str, Any]  # "X"/"Y": worst line's ISO figures and straightness
    nodes: list[dict[str, Any]]  # one per grid node: target, mean 2-D error (um), per pass direction, n
    notes: list[str] = field(default_factory=list)


def _lines(target_mm: np.ndarray, valid: np.ndarray, moving: int) -> list[tuple[float, np.ndarray]]:
    """Groups of captures with the other axis' target equal and >= MIN_LINE_TARGETS distinct targets."""
    other = 1 - moving
    key = np.round(target_mm[:, other] / LINE_TOL_MM).astype(np.int64)
    out = []
    for k in np.unique(key[valid]):
        sel = np.flatnonzero(valid & (key == k))
        if np.unique(np.round(target_mm[sel, moving] / LINE_TOL_MM)).size >= MIN_LINE_TARGETS:
            out.append((float(target_mm[sel[0], other]), sel))
    return out


def _straightness(t_along: np.ndarray, cross_um: np.ndarray, sigma_um: np.ndarray) -> tuple[float, float, dict]:
    """Peak-to-valley of the cross deviation about its least-squares line (ISO 230-1 reference line), the noise's
    selection taken out as every p-v (core.resolution.profile_span), the median 1-sigma, and that profile."""
    targets, j = target_index(t_along)
    n = np.bincount(j, minlength=targets.size)
    mean = np.bincount(j, cross_um, minlength=targets.size) / n
    A = np.column_stack([np.ones(targets.size), targets - targets.mean()])
    coef, *_ = np.linalg.lstsq(A, mean, rcond=None)
    resid = mean - A @ coef
    off_line = cross_um - (coef[0] + coef[1] * (t_along - targets.mean()))  # every capture off the same line
    span = profile_span(off_line, sigma_um, t_along, np.isfinite(off_line))
    return float(np.ptp(resid) if span.span is None else span.span), float(np.median(sigma_um)), span.to_dict("um")


def planar_figures(
    target_mm: np.ndarray,
    approach: np.ndarray,
    run: np.ndarray,
    direction: np.ndarray,
    deviation_um: np.ndarray,
    sigma_um: np.ndarray,
    valid: np.ndarray,
    G: np.ndarray,
    cov_G: np.ndarray,
    out_of_plane_um: np.ndarray | None = None,
    out_of_plane_sigma_um: np.ndarray | None = None,
) -> PlanarFigures:
    """All planar figures from per-capture deviations (K, 2) um and sigmas (K, 2) um.

    ``out_of_plane_um`` (K,) with its sigma (core.planar_flatness) adds each
    line's straightness along the plane normal.
    """
    geometry = axis_geometry(G, cov_G)
    notes: list[str] = []
    lines: list[LineFigures] = []
    raw: list[tuple[dict[str, Any], tuple] | None] = []  # per line: its uncorrected figures and noise-correction inputs
    names = ("X", "Y")
    for moving in range(2):
        other = 1 - moving
        for at, sel in _lines(target_mm, valid, moving):
            p_v, s, span = _straightness(target_mm[sel, moving], deviation_um[sel, other], sigma_um[sel, other])
            oop = None
            if out_of_plane_um is not None and out_of_plane_sigma_um is not None:
                oop = _straightness(target_mm[sel, moving], out_of_plane_um[sel], out_of_plane_sigma_um[sel])[2]
            iso = None
            signs = approach[sel, moving]
            runs_key = run[sel] * 2 + (direction[sel] > 0)
            noise_in = (target_mm[sel, moving], signs, runs_key, deviation_um[sel, moving],
                        independent_sigma_um(sigma_um[sel, moving]))
            raw.append(None)
            try:
                iso = figures_for_session(target_mm[sel, moving], np.where(signs > 0, "+", "-"), runs_key,
                                          deviation_um[sel, moving], None)
                if iso.get("iso230_2"):  # the per-view noise taken out, as a line's (issue 35)
                    raw[-1] = (dict(iso["iso230_2"]), noise_in)
                    corr = noise_corrected_iso(*noise_in[:4], np.ones(sel.size, bool), noise_in[4])
                    iso["iso230_2"] = apply_noise_correction(iso["iso230_2"], corr)
            except Exception as exc:  # a line too short for the figures: say so, keep the rest
                notes.append(f"{names[moving]} line at {names[other]}={at:g} mm: no ISO 230-2 figures ({exc})")
            lines.append(LineFigures(names[moving], at, int(np.unique(target_mm[sel, moving]).size), p_v, s, iso,
                                     span, oop))
    per_axis: dict[str, Any] = {}
    for name in names:
        own = [ln for ln in lines if ln.axis == name]
        if not own:
            notes.append(f"no line along {name} with {MIN_LINE_TARGETS} or more targets: no {name} figures")
            continue
        worst = max(own, key=lambda ln: ln.straightness_um or 0.0)
        per_axis[name] = {
            "lines": len(own),
            "straightness_um_max": worst.straightness_um,
            "straightness_at_mm": worst.at_mm,
            "straightness_sigma_um": worst.straightness_sigma_um,
            "straightness": worst.straightness,
            "iso230_2": _worst_iso([(ln, raw[i]) for i, ln in enumerate(lines) if ln.axis == name]),
        }
        with_oop = [ln for ln in own if ln.out_of_plane and ln.out_of_plane.get("span_um") is not None]
        if with_oop:
            w = max(with_oop, key=lambda ln: ln.out_of_plane["span_um"])
            per_axis[name]["out_of_plane"] = {**w.out_of_plane, "at_mm": w.at_mm}
    return PlanarFigures(geometry, lines, per_axis, node_errors(target_mm, direction, deviation_um, sigma_um, valid),
                         notes)


def _worst_iso(lines: list[tuple[LineFigures, tuple[dict[str, Any], tuple] | None]]) -> dict[str, Any] | None:
    """The ISO figures of the line with the largest accuracy A (the figure a spec is judged on), the noise taken
    out with that choice (:func:`noise_corrected_worst`: the worst of several noisy lines is biased upwards by
    the choice itself, which no line's own correction sees)."""
    with_iso = [(ln, r) for ln, r in lines if r is not None and ln.iso230_2 and _accuracy(ln.iso230_2) is not None]
    if not with_iso:
        return None
    picked = noise_corrected_worst([r[1] for _, r in with_iso])
    if picked is None:
        return None
    i, corr = picked
    ln, (measured, _) = with_iso[i]
    return {"at_mm": ln.at_mm, **ln.iso230_2, "iso230_2": apply_noise_correction(measured, corr)}


def _accuracy(figs: dict[str, Any]) -> float | None:
    """Bidirectional accuracy A of a line (else the one direction there is)."""
    iso = figs.get("iso230_2") or {}
    for key in ("A_um", "A_up_um", "A_down_um"):
        if isinstance(iso.get(key), (int, float)):
            return float(iso[key])
    return None


def node_errors(target_mm: np.ndarray, direction: np.ndarray, deviation_um: np.ndarray, sigma_um: np.ndarray,
                valid: np.ndarray) -> list[dict[str, Any]]:
    """The mean 2-D error vector at every grid node, overall and per pass direction."""
    key = np.round(target_mm / LINE_TOL_MM).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    nodes = []
    for n, f in enumerate(first):
        sel = (inv == n) & valid
        entry: dict[str, Any] = {"target_mm": [float(target_mm[f, 0]), float(target_mm[f, 1])], "n": int(sel.sum())}
        if sel.any():
            entry["error_um"] = [float(v) for v in deviation_um[sel].mean(axis=0)]
            entry["sigma_um"] = [float(v) for v in np.sqrt(np.mean(sigma_um[sel] ** 2, axis=0) / sel.sum())]
            for sign, label in ((1, "forward"), (-1, "backward")):
                s = sel & (direction == sign)
                if s.any():
                    entry[f"error_{label}_um"] = [float(v) for v in deviation_um[s].mean(axis=0)]
        else:
            entry["error_um"] = None
        nodes.append(entry)
    return nodes
