"""The checks a live capture runs on every frame and every running estimate, so a fault is seen at its stop.

Per frame (:class:`FrameChecks`): the board found and clear of the image
border, the exposure (mean grey) and the sharpness against the frames just
before. Per running estimate (:class:`EstimateChecks`): the new views' residual
RMS with the solution so far held (it grows when the camera moved on its
mount) and the views the estimator's outlier round rejects (off the line). Each flag
names the capture index it happened at; a fault is flagged once, at its
first frame, and the baseline starts again from the new level.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

EXPOSURE_RATIO = 1.15  # mean grey level up or down by 15 % from the frames before
SHARPNESS_RATIO = 1.5  # contrast-normalized sharpness up or down by 50 %
RMS_RATIO = 3.0  # a view's RMS this many times the median of the views before
RMS_FLOOR_PX = 0.3  # ... and at least this much above it: noise alone never does that
WINDOW = 8  # frames in the moving baseline


@dataclass(frozen=True)
class LiveFlag:
    """One finding: ``kind`` is "board", "edge", "exposure", "sharpness", "outlier" or "rms"."""

    kind: str
    index: int  # capture index of the frame it happened at
    message: str


def border_margin_px(corners_px: np.ndarray, image_size: tuple[int, int]) -> float:
    """Smallest distance of a seen corner to the image border (px)."""
    xy = np.asarray(corners_px, float).reshape(-1, 2)
    xy = xy[np.isfinite(xy).all(axis=1)]
    if not len(xy):
        return float("nan")
    w, h = image_size
    return float(min(xy[:, 0].min(), xy[:, 1].min(), w - 1 - xy[:, 0].max(), h - 1 - xy[:, 1].max()))


def _off(value: float, base: float, ratio: float) -> bool:
    return bool(base > 0 and value > 0 and abs(np.log(value / base)) > np.log(ratio))


@dataclass
class FrameChecks:
    """Board in view, exposure and sharpness of each new frame against a moving baseline."""

    edge_px: float = 10.0  # closer to the border than this: the board is about to leave the view
    _grey: list[float] = field(default_factory=list)
    _sharp: list[float] = field(default_factory=list)
    _lost: bool = False
    _edge: bool = False

    def check(self, index: int, corners_px: np.ndarray | None, reason: str, mean_grey: float, sharpness: float,
              image_size: tuple[int, int]) -> list[LiveFlag]:
        flags: list[LiveFlag] = []
        if corners_px is None:
            if not self._lost:
                flags.append(LiveFlag("board", index, f"frame {index}: board not found ({reason or 'out of view'}); "
                                                      "the board left the view or is covered"))
            self._lost = True
        else:
            self._lost = False
            near = border_margin_px(corners_px, image_size) < self.edge_px
            if near and not self._edge:
                flags.append(LiveFlag("edge", index, f"frame {index}: the board is at the edge of the view "
                                                     f"(a corner within {self.edge_px:g} px of the border)"))
            self._edge = near
        grey_base = float(np.median(self._grey)) if self._grey else mean_grey
        if _off(mean_grey, grey_base, EXPOSURE_RATIO):
            flags.append(LiveFlag("exposure", index, f"frame {index}: exposure jumped (mean grey {mean_grey:.0f}, "
                                                     f"{grey_base:.0f} before); check light and camera gain"))
            self._grey, self._sharp = [], []
        # sharpness over contrast: an exposure change alone leaves it, a blur or a focus shift does not
        contrast_sharp = sharpness / max(mean_grey, 1.0) ** 2
        sharp_base = float(np.median(self._sharp)) if self._sharp else contrast_sharp
        if _off(contrast_sharp, sharp_base, SHARPNESS_RATIO):
            flags.append(LiveFlag("sharpness", index, f"frame {index}: sharpness changed by "
                                                      f"{contrast_sharp / sharp_base:.2f}x; check focus and vibration"))
            self._sharp = []
        self._grey = (self._grey + [mean_grey])[-WINDOW:]
        self._sharp = (self._sharp + [contrast_sharp])[-WINDOW:]
        return flags


@dataclass
class EstimateChecks:
    """New views against the solution so far (a camera moving on its mount), and the estimator's outliers."""

    _flagged: set[tuple[str, int]] = field(default_factory=set)
    _high: set[int] = field(default_factory=set)  # views whose RMS was high against the solution before them

    def check_new_views(self, index: np.ndarray, rms_px: np.ndarray, base_rms_px: float) -> list[LiveFlag]:
        """``rms_px`` of the views ``index`` under the last solution, whose own views had ``base_rms_px``."""
        rms = np.asarray(rms_px, float)
        high = np.isfinite(rms) & (rms > max(RMS_RATIO * base_rms_px, base_rms_px + RMS_FLOOR_PX))
        flags = []
        for i in range(len(rms)):
            at = int(index[i])
            if high[i] and at - 1 not in self._high:  # a stretch of views off the same way is one finding
                flags.append(LiveFlag("rms", at, f"frame {at}: residual RMS grew from {base_rms_px:.2f} px to "
                                                 f"{rms[i]:.2f} px; the camera may have moved on its mount"))
            if high[i]:
                self._high.add(at)
        return flags

    def check(self, index: np.ndarray, outlier: np.ndarray, outlier_reason: list[str]) -> list[LiveFlag]:
        """The outliers of one estimate of the views ``index`` (capture indices, capture order)."""
        flags: list[LiveFlag] = []
        out = np.asarray(outlier, bool)
        for i in np.flatnonzero(out):
            key = ("outlier", int(index[i]))
            if key in self._flagged:
                continue
            self._flagged.add(key)
            if i > 0 and ("outlier", int(index[i - 1])) in self._flagged:
                continue  # one stretch of views off the line is one finding, at its first frame
            flags.append(LiveFlag("outlier", int(index[i]), f"frame {int(index[i])}: view off the line "
                                                             f"({outlier_reason[i] or 'outlier'})"))
        return flags
