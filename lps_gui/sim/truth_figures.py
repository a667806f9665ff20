"""Every headline figure and every "resolved" finding of a simulated session against the simulator's truth.

A report's figure is only worth its error bar; a simulated session knows the
truth, so it can say whether each error bar held (issue 35). From results.json's
sections alone (:class:`CheckedValues`: the builder's values, or a finished
document's): the truth columns :func:`lps_gui.sim.truth.truth_comparison` put
beside each position, its ``truth_comparison`` and ``error_motions.truth``:

- :func:`figure_checks`: each headline figure (ISO 230-2 A, E, R, B, M, max
  |deviation|, scale, straightness, angles, error motions; on a gantry squareness,
  scale and straightness per axis) with the truth reduced by the same rule, the
  error, the U (k = 2) the report prints, and z = error / (U / k);
- :func:`finding_checks`: every "resolved" call (straightness, image rotation,
  roll/pitch/yaw, error motions) beside the truth's size: a call is false when
  the truth is under half what noise alone could give;
- :func:`self_check`: the verdict page 1, the console and results.json ``flags``
  carry: mean (error/sigma)^2 of the per-stop positions above 3, a figure off by
  more than 2 U, or a resolved finding the truth does not have.

``benchmarks/honesty.py`` pools these rows over seeds and kinds of session.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lps_gui.core.metrology.iso230 import figures_for_session
from lps_gui.core.metrology.iso230_run import fit_weights_sigma_um
from lps_gui.core.metrology.resolution import per_target_means

K = 2.0  # the coverage factor of every U the report prints
Z_MS_LIMIT = 3.0  # mean (error/sigma)^2 above this: the sigmas do not hold
FALSE_FRACTION = 0.5  # a resolved finding whose truth is under this fraction of the noise threshold is false
ISO_KEYS = ("A_um", "E_um", "R_um", "B_um", "M_um")
ANGLES = ("roll", "pitch", "yaw")
MOTION_ANGLES = {"EAX": "roll", "EBX": "pitch", "ECX": "yaw"}


@dataclass(frozen=True)
class CheckedValues:
    """What the self-check compares with truth, as JSON values: the builder's (passed down while the results are
    built, :func:`self_check_section`) or a finished results.json's (:meth:`of_document`, for readers)."""

    positions: Sequence[Mapping[str, Any]]
    figures: Mapping[str, Any]
    uncertainty: Mapping[str, Any]
    truth_comparison: Mapping[str, Any] | None
    error_motions: Mapping[str, Any] | None = None
    planar: bool = False
    asme: Mapping[str, Any] | None = None  # results.json ``asme_b5_64`` (a settling test's time has a truth)

    @classmethod
    def of_document(cls, results: Mapping[str, Any]) -> CheckedValues:
        """The values of a finished results.json document (a reader: benchmarks/honesty.py, tests)."""
        return cls(results.get("positions") or [], results.get("figures") or {}, results.get("uncertainty") or {},
                   results.get("truth_comparison"), results.get("error_motions"),
                   len(results.get("axes") or ["X"]) == 2, results.get("asme_b5_64"))


def checked(values: CheckedValues | Mapping[str, Any]) -> CheckedValues:
    """``values`` as :class:`CheckedValues`: a finished document's sections, or the builder's values as they are."""
    return values if isinstance(values, CheckedValues) else CheckedValues.of_document(values)


def _col(rows: list[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else float(r[key]) for r in rows], dtype=float)


def _check(name: str, unit: str, value: Any, truth: Any, U: Any, shown: Any = True) -> dict[str, Any] | None:
    """One figure's row; None when the figure, its truth or its U is missing, or the report does not state it
    (``shown`` False: a p-v or max |angle| noise alone could give is printed as "not resolved", no value)."""
    if shown is False or value is None or truth is None or U is None or not all(math.isfinite(float(v)) for v in (value, truth, U)):
        return None
    err = float(value) - float(truth)
    sigma = float(U) / K
    return {"figure": name, "unit": unit, "value": float(value), "truth": float(truth), "error": err,
            "U_k2": float(U), "z": err / sigma if sigma > 0 else math.inf}


def _target_means(values: np.ndarray, target: np.ndarray, ok: np.ndarray) -> np.ndarray | None:
    """The per-target means of ``values`` over ``ok``, targets sorted, as the report takes them
    (:func:`~lps_gui.core.metrology.resolution.per_target_means`); None without a finite value."""
    keep = ok & np.isfinite(values)
    if not keep.any():
        return None
    return per_target_means(values[keep], np.zeros(int(keep.sum())), target[keep], difference_order=0)[2]


def _per_target_span(values: np.ndarray, target: np.ndarray, ok: np.ndarray) -> float | None:
    """p-v of the per-target means of ``values`` over ``ok`` (how the report's spans are taken)."""
    means = _target_means(values, target, ok)
    return float(np.ptp(means)) if means is not None and means.size >= 2 else None


def _max_abs_about_mean(values: np.ndarray, target: np.ndarray, ok: np.ndarray) -> float | None:
    """max |x| of the per-target means of ``values`` over ``ok`` about their mean (how the report's max |angle|
    is taken: :func:`~lps_gui.core.metrology.resolution.centred_target_means`)."""
    means = _target_means(values, target, ok)
    return None if means is None else float(np.max(np.abs(means - means.mean())))


def _line_truth_dev(pos: list[dict[str, Any]]) -> np.ndarray | None:
    """The true deviation per position the estimate measures: at the board plane when the truth has it."""
    for key in ("truth_plane_deviation_um", "truth_deviation_um"):
        v = _col(pos, key)
        if np.isfinite(v).any():
            return v
    return None


def line_figure_checks(values: CheckedValues | Mapping[str, Any]) -> list[dict[str, Any]]:
    """The headline figures of a one-axis session against truth (rows of :func:`_check`)."""
    v = checked(values)
    pos = v.positions
    dev = _line_truth_dev(pos)
    if dev is None:
        return []
    used = np.array([bool(r.get("used")) for r in pos]) & np.isfinite(dev)
    target = _col(pos, "target_mm")
    run = np.array([r.get("run", 1) for r in pos])
    direction = np.array([r.get("direction", "+") for r in pos])
    noise = _col(pos, "sigma_um")  # the same reduction as the estimate's: its scale is a slope weighted by 1/sigma^2
    weights = fit_weights_sigma_um(noise, used) if np.isfinite(noise[used]).all() else None
    true = figures_for_session(target, direction, run, dev, valid=used, sigma_um=weights)
    figs = v.figures
    Uk = v.uncertainty.get("figures_k2") or {}
    out = []
    iso, true_iso = figs.get("iso230_2") or {}, true.get("iso230_2") or {}
    for key in ISO_KEYS:
        out.append(_check(key[:-3], "um", iso.get(key), true_iso.get(key), Uk.get(key)))
    single, true_single = figs.get("single_run") or {}, true.get("single_run") or {}
    out.append(_check("max |deviation|", "um", single.get("max_abs_deviation_um"),
                      true_single.get("max_abs_deviation_um"), Uk.get("max_abs_deviation_um")))
    out.append(_check("scale", "ppm", single.get("scale_ppm"), true_single.get("scale_ppm"), Uk.get("scale_ppm")))
    straight = figs.get("straightness") or {}
    for j in (1, 2):
        truth = _per_target_span(_col(pos, f"truth_straightness_um_{j}"), target, used)
        st = straight.get(f"v{j}") or {}
        out.append(_check(f"straightness v{j}", "um", st.get("span_um"), truth, Uk.get(f"straightness_span_{j}"),
                          st.get("resolved")))
    angles = figs.get("angles_resolution") or {}
    for name in ANGLES:
        truth = _max_abs_about_mean(_col(pos, f"truth_{name}_urad"), target, used)
        a = angles.get(name) or {}
        out.append(_check(f"max |{name}|", "urad", a.get("max_abs_urad"), truth, Uk.get(f"max_abs_{name}"),
                          a.get("resolved")))
    out += motion_checks(v, target, used)
    out.append(settling_check(v.asme))
    return [c for c in out if c is not None]


def settling_check(asme: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """A settling test's headline figure, the settling time (the longest over its moves, s), against the simulated
    stage's ringing (``asme_b5_64.settling.truth``: every move rings alike); None without a settling test."""
    st = (asme or {}).get("settling") or {}
    return _check("settling time", "s", st.get("settling_time_s"), (st.get("truth") or {}).get("settling_time_s"),
                  st.get("settling_time_U_s"))


def motion_checks(values: CheckedValues | Mapping[str, Any], target: np.ndarray, used: np.ndarray
                  ) -> list[dict[str, Any]]:
    """The angular error motions' spans (EAX, EBX, ECX) against ``error_motions.truth``; U = k times the span's
    own standard uncertainty (``u_span``, the noise's selection taken out), else k sqrt 2 sigma of one mean."""
    em = checked(values).error_motions or {}
    out = []
    for iso, m in (em.get("motions") or {}).items():
        t = (em.get("truth") or {}).get(iso) or {}
        true_values = np.array([np.nan if v is None else v for v in t.get("true_values") or []], dtype=float)
        unit = m.get("unit") or "urad"
        if true_values.size != target.size or (U := _span_U(m, unit)) is None:
            continue
        out.append(_check(f"{iso} p-v", unit, m.get(f"span_{unit}"), _per_target_span(true_values, target, used),
                          U, m.get("resolved")))
    return out


def _span_U(span: dict[str, Any], unit: str) -> float | None:
    """U (k = 2) of a p-v as the report states it: from ``u_span``, else k sqrt 2 ``sigma`` (older documents)."""
    if span.get(f"u_span_{unit}") is not None:
        return K * float(span[f"u_span_{unit}"])
    return None if span.get(f"sigma_{unit}") is None else K * math.sqrt(2.0) * float(span[f"sigma_{unit}"])


def planar_figure_checks(values: CheckedValues | Mapping[str, Any]) -> list[dict[str, Any]]:
    """A gantry's headline figures against truth: squareness, scale and straightness per axis, ISO 230-2 per axis."""
    v = checked(values)
    pl = v.figures.get("planar") or {}
    tc = v.truth_comparison or {}
    unc = v.uncertainty.get("per_axis") or {}
    out = []
    sq_sigma = pl.get("squareness_sigma_urad")
    if tc.get("squareness_error_urad") is not None and sq_sigma is not None:
        out.append(_check("squareness", "urad", pl.get("squareness_urad"),
                          pl["squareness_urad"] - tc["squareness_error_urad"], K * sq_sigma))
    for axis in ("X", "Y"):
        a, ax = (pl.get("per_axis") or {}).get(axis) or {}, axis.lower()
        Uk = (unc.get(axis) or {}).get("figures_k2") or {}
        err = tc.get(f"scale_{ax}_error_ppm")
        if err is not None and pl.get(f"scale_{ax}_ppm") is not None:
            U = Uk.get("scale_ppm") or (None if pl.get(f"scale_{ax}_sigma_ppm") is None
                                        else K * pl[f"scale_{ax}_sigma_ppm"])
            out.append(_check(f"scale {axis}", "ppm", pl[f"scale_{ax}_ppm"], pl[f"scale_{ax}_ppm"] - err, U))
        st = a.get("straightness") or {}
        out.append(_check(f"straightness {axis}", "um", a.get("straightness_um_max"), tc.get(f"straightness_{ax}_um"),
                          _span_U({**st, "sigma_um": a.get("straightness_sigma_um")}, "um"), st.get("resolved")))
        iso = ((a.get("iso230_2") or {}).get("iso230_2")) or {}
        true_iso = tc.get(f"iso230_2_{ax}") or {}
        for key in ISO_KEYS:
            out.append(_check(f"{key[:-3]} {axis}", "um", iso.get(key), true_iso.get(key), Uk.get(key)))
    return [c for c in out if c is not None]


def figure_checks(values: CheckedValues | Mapping[str, Any]) -> list[dict[str, Any]]:
    """Every headline figure of a simulated session beside its truth, U (k = 2) and z."""
    v = checked(values)
    if not v.truth_comparison:
        return []
    return planar_figure_checks(v) if v.planar else line_figure_checks(v)


def _finding(name: str, resolved: Any, truth: float | None, noise: Any) -> dict[str, Any] | None:
    if resolved is None or truth is None or noise is None:
        return None
    return {"finding": name, "resolved": bool(resolved), "truth": float(truth), "noise": float(noise),
            "truth_has_it": bool(truth >= FALSE_FRACTION * float(noise)),
            "false": bool(resolved) and truth < FALSE_FRACTION * float(noise)}


def finding_checks(values: CheckedValues | Mapping[str, Any]) -> list[dict[str, Any]]:
    """Every "resolved" call of a simulated session beside the truth's size and the noise threshold."""
    v = checked(values)
    pos = v.positions
    if not v.truth_comparison or not pos:
        return []
    figs = v.figures
    out = []
    if v.planar:
        tc = v.truth_comparison
        for axis, a in ((figs.get("planar") or {}).get("per_axis") or {}).items():
            st = a.get("straightness") or {}
            out.append(_finding(f"straightness {axis}", st.get("resolved"), tc.get(f"straightness_{axis.lower()}_um"),
                                st.get("noise_span_um")))
        return [f for f in out if f is not None]
    used = np.array([bool(r.get("used")) for r in pos])
    target = _col(pos, "target_mm")
    for j in (1, 2):
        st = (figs.get("straightness") or {}).get(f"v{j}") or {}
        out.append(_finding(f"straightness v{j}", st.get("resolved"),
                            _per_target_span(_col(pos, f"truth_straightness_um_{j}"), target, used),
                            st.get("noise_span_um")))
    rot = figs.get("image_rotation") or {}
    out.append(_finding("image rotation", rot.get("resolved"),
                        _per_target_span(_col(pos, "truth_image_rotation_urad"), target, used),
                        rot.get("noise_span_urad")))
    for name in ANGLES:
        a = (figs.get("angles_resolution") or {}).get(name) or {}
        out.append(_finding(f"max |{name}|", a.get("resolved"),
                            _max_abs_about_mean(_col(pos, f"truth_{name}_urad"), target, used),
                            a.get("noise_max_abs_urad")))
    em = v.error_motions or {}
    for iso, m in (em.get("motions") or {}).items():
        true_values = _motion_truth(iso, em, pos)
        if true_values is None:
            continue
        unit = m.get("unit") or "um"
        out.append(_finding(iso, m.get("resolved"), _per_target_span(true_values, target, used),
                            m.get(f"noise_span_{unit}")))
    return [f for f in out if f is not None]


def _motion_truth(iso: str, em: dict[str, Any], pos: list[dict[str, Any]]) -> np.ndarray | None:
    """A line's true error motion per position: the angles from ``error_motions.truth``, positioning and
    straightness from the truth columns (at the board plane; the carriage's when no angle moves it)."""
    t = (em.get("truth") or {}).get(iso) or {}
    if t.get("true_values"):
        v = np.array([np.nan if x is None else x for x in t["true_values"]], dtype=float)
        return v if v.size == len(pos) else None
    key = {"EXX": "truth_deviation_um", "EYX": "truth_straightness_um_1", "EZX": "truth_straightness_um_2"}.get(iso)
    if key is None:
        return None
    v = _col(pos, key)
    return v if np.isfinite(v).any() else None


def self_check(values: CheckedValues | Mapping[str, Any]) -> dict[str, Any] | None:
    """Does the truth contradict the report? None for a real session; else ``{"passed", "problems"}``, each
    problem one line naming the figure and by how much."""
    checked_values = checked(values)
    tc = checked_values.truth_comparison
    if not tc:
        return None
    problems = []
    z_ms = tc.get("board_plane_z_mean_square", tc.get("z_mean_square"))
    if z_ms is not None and z_ms > Z_MS_LIMIT:
        problems.append(f"per-stop positions: mean (error/sigma)^2 {z_ms:.1f} against truth (above {Z_MS_LIMIT:g}): "
                        "the sigmas and bands are too small")
    for key, what in (("straightness_z_mean_square_1", "straightness v1"), ("straightness_z_mean_square_2",
                                                                            "straightness v2")):
        if (v := tc.get(key)) is not None and v > Z_MS_LIMIT:
            problems.append(f"{what}: mean (error/sigma)^2 {v:.1f} against truth (above {Z_MS_LIMIT:g})")
    targets = tc.get("targets") or {}
    if (v := targets.get("z_mean_square")) is not None and v > Z_MS_LIMIT:
        problems.append(f"target poses: mean (error/sigma)^2 {v:.1f} against truth (above {Z_MS_LIMIT:g})")
    for c in figure_checks(checked_values):
        if abs(c["z"]) > 2 * K:
            problems.append(f"{c['figure']} {c['value']:.4g} {c['unit']}, truth {c['truth']:.4g}: off by "
                            f"{abs(c['error']) / c['U_k2']:.1f} x its U (k = 2) {c['U_k2']:.3g} {c['unit']}")
    for f in finding_checks(checked_values):
        if f["false"]:
            problems.append(f"{f['finding']} called resolved, but the truth is {f['truth']:.3g} (noise threshold "
                            f"{f['noise']:.3g})")
    return {"passed": not problems, "problems": problems}


def truth_check_flag(check: dict[str, Any] | None) -> dict[str, Any] | None:
    """results.json ``flags`` entry of a failed self-check (kind ``truth_check``, no view index)."""
    if not check or check["passed"]:
        return None
    return {"index": None, "kind": "truth_check",
            "message": "simulated session: the truth contradicts this report: " + "; ".join(check["problems"])}


def self_check_section(values: CheckedValues) -> tuple[dict[str, Any] | None, dict[str, Any] | None]:
    """A simulated session's results checked against its truth (issue 35: simulated sessions check themselves),
    from the values the builders made: (``truth_comparison.self_check``, the ``truth_check`` flag when it fails);
    (None, None) for a real session."""
    check = self_check(values)
    return check, truth_check_flag(check)
