"""One-axis motion profiles: trapezoidal moves and controlled stops, evaluated at any time.

The simulated stage (and through it every emulator serving it) plans every move as a
list of constant-acceleration segments, so its position, velocity and state
at any clock time follow from a closed form and nothing has to tick in real
time. Units: mm, s, mm/s, mm/s^2.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Segment:
    """Constant acceleration from ``t0`` for ``dur_s``: x(t) = x0 + v0 dt + a dt^2 / 2."""

    t0: float
    x0_mm: float
    v0_mm_s: float
    a_mm_s2: float
    dur_s: float

    @property
    def t_end(self) -> float:
        return self.t0 + self.dur_s

    def at(self, t: float) -> tuple[float, float]:
        """Position (mm) and velocity (mm/s) at time ``t`` (clamped to the segment)."""
        dt = min(max(t - self.t0, 0.0), self.dur_s)
        return self.x0_mm + self.v0_mm_s * dt + 0.5 * self.a_mm_s2 * dt * dt, self.v0_mm_s + self.a_mm_s2 * dt


@dataclass(frozen=True)
class Profile:
    """A planned motion of one axis from rest to rest (or to a stop), as segments in time order.

    ``kind`` says what state (``StageStatus.state``) it shows while running ("Run", "Jog", "Home"),
    ``direction`` the sign of travel (+1/-1, 0 for a null move) used for backlash.
    """

    axis: int
    kind: str
    segments: tuple[Segment, ...]
    start_mm: float
    end_mm: float
    t0: float
    feed_mm_min: float

    @property
    def t_end(self) -> float:
        return self.segments[-1].t_end if self.segments else self.t0

    @property
    def direction(self) -> int:
        return int(math.copysign(1, self.end_mm - self.start_mm)) if self.end_mm != self.start_mm else 0

    def at(self, t: float) -> tuple[float, float]:
        """Position (mm) and velocity (mm/s) at time ``t``; before start / after end it rests."""
        if not self.segments or t <= self.t0:
            return self.start_mm, 0.0
        for seg in self.segments:
            if t < seg.t_end:
                return seg.at(t)
        return self.end_mm, 0.0


def trapezoid(
    axis: int, kind: str, t0: float, x0_mm: float, x1_mm: float, feed_mm_min: float, accel_mm_s2: float
) -> Profile:
    """Plan a rest-to-rest move with a velocity limit and a symmetric acceleration limit.

    Triangular when the distance is too short to reach the feed rate.
    """
    dist = abs(x1_mm - x0_mm)
    sign = 1.0 if x1_mm >= x0_mm else -1.0
    v_max = feed_mm_min / 60.0
    if dist == 0.0 or v_max <= 0.0 or accel_mm_s2 <= 0.0:
        return Profile(axis, kind, (), x0_mm, x1_mm, t0, feed_mm_min)
    a = accel_mm_s2
    d_ramp = v_max * v_max / (2.0 * a)
    if 2.0 * d_ramp >= dist:  # triangle: never reaches v_max
        v_peak = math.sqrt(a * dist)
        t_ramp = v_peak / a
        t_cruise = 0.0
    else:
        v_peak = v_max
        t_ramp = v_max / a
        t_cruise = (dist - 2.0 * d_ramp) / v_max
    s1 = Segment(t0, x0_mm, 0.0, sign * a, t_ramp)
    x1, v1 = s1.at(s1.t_end)
    segs = [s1]
    if t_cruise > 0:
        s2 = Segment(s1.t_end, x1, sign * v_peak, 0.0, t_cruise)
        segs.append(s2)
        x1, v1 = s2.at(s2.t_end)
    segs.append(Segment(segs[-1].t_end, x1, v1, -sign * a, t_ramp))
    return Profile(axis, kind, tuple(segs), x0_mm, x1_mm, t0, feed_mm_min)


def stop_from(profile: Profile, t: float, accel_mm_s2: float) -> Profile:
    """The controlled deceleration (feed hold, jog cancel) of ``profile`` started at time ``t``."""
    x, v = profile.at(t)
    if v == 0.0 or accel_mm_s2 <= 0:
        return Profile(profile.axis, profile.kind, (), x, x, t, profile.feed_mm_min)
    a = -math.copysign(accel_mm_s2, v)
    dur = abs(v) / accel_mm_s2
    seg = Segment(t, x, v, a, dur)
    return Profile(profile.axis, profile.kind, (seg,), x, seg.at(seg.t_end)[0], t, profile.feed_mm_min)


def duration_s(distance_mm: float, feed_mm_min: float, accel_mm_s2: float) -> float:
    """Time a rest-to-rest move of ``distance_mm`` takes (for timeouts and ETAs)."""
    return trapezoid(0, "Run", 0.0, 0.0, abs(distance_mm), feed_mm_min, accel_mm_s2).t_end
