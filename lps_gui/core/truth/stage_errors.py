"""The true motion of a simulated stage: one error model shared by every simulator.

The point simulator, the rendered-image simulator, the simulated stage and
the GRBL emulator all ask this model where the carriage really is, so the
truth a test compares against is one object. Error motions follow ISO 230-1
vocabulary: positioning error along the axis (scale, lead-screw periodic
error, backlash, repeatability), two straightness errors and three angular
errors (roll, pitch, yaw). Two effects of small and quick moves (the ASME B5.64
incremental-step and settling tests): a dead band (stick-slip: a commanded
move shorter than ``dead_band_um`` does not move the carriage,
:meth:`StageErrorModel.reached_mm`) and the ringing after a move
(:class:`Vibration`, with its true settling time).

An XY gantry (SPEC 10) is two such axes, each a function of its own
commanded position, plus squareness: :class:`PlanarErrorModel`. Straightness
profile 0 of an axis is in the plane (X's along y, Y's along x), profile 1
out of the plane (along the plane normal).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ErrorProfile:
    """A smooth error as a function of the commanded axis position x (mm).

    value(x) = sum_k poly[k] * (x/1000)^k + amplitude * sin(2 pi x / period_mm + phase_rad)
    in the profile's own unit (um for lengths, urad for angles); polynomial
    in metres of travel so coefficients read as "um per m" and "um per m^2".
    """

    poly: tuple[float, ...] = ()
    amplitude: float = 0.0
    period_mm: float = 0.0
    phase_rad: float = 0.0

    def __call__(self, x_mm: np.ndarray) -> np.ndarray:
        x = np.asarray(x_mm, dtype=float)
        xm = x / 1000.0
        out = np.zeros_like(x)
        for k, c in enumerate(self.poly):
            out = out + c * xm**k
        if self.amplitude and self.period_mm:
            out = out + self.amplitude * np.sin(2.0 * np.pi * x / self.period_mm + self.phase_rad)
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> "ErrorProfile":
        d = d or {}
        return cls(
            poly=tuple(float(c) for c in d.get("poly", ())),
            amplitude=float(d.get("amplitude", 0.0)),
            period_mm=float(d.get("period_mm", 0.0)),
            phase_rad=float(d.get("phase_rad", 0.0)),
        )


@dataclass(frozen=True)
class TruePose:
    """Where the carriage really is, for K commanded positions."""

    axis_mm: np.ndarray  # shape (K,): true position along the motion axis
    straightness_um: np.ndarray  # shape (K, 2): along v1, v2 of the motion frame
    angles_urad: np.ndarray  # shape (K, 3): roll (about u), pitch (v1), yaw (v2)


@dataclass(frozen=True)
class StageErrorModel:
    """True-position error model of a lead-screw stage.

    Positioning error e(x) = scale_ppm*1e-6*x + periodic_um*sin(2 pi x/pitch_mm + phase)
    - backlash_um/2 * approach direction + N(0, repeatability_um): a target
    approached moving up (+1) stops short by half the backlash, moving down
    (-1) overshoots by half. The angles are smooth profiles plus, per stop,
    N(0, angle_noise_urad) about each axis (a carriage settling on its
    bearings a little differently every time). ``dead_band_um`` (stick-slip) acts on the
    sequence of commands, not on one position: see :meth:`reached_mm`.
    """

    scale_ppm: float = 0.0
    periodic_um: float = 0.0
    pitch_mm: float = 5.0
    periodic_phase_rad: float = 0.0
    backlash_um: float = 0.0
    repeatability_um: float = 0.0
    straightness_um: tuple[ErrorProfile, ErrorProfile] = field(
        default_factory=lambda: (ErrorProfile(), ErrorProfile())
    )
    roll_urad: ErrorProfile = field(default_factory=ErrorProfile)
    pitch_urad: ErrorProfile = field(default_factory=ErrorProfile)
    yaw_urad: ErrorProfile = field(default_factory=ErrorProfile)
    angle_noise_urad: float = 0.0
    dead_band_um: float = 0.0  # stick-slip: a move shorter than this leaves the carriage where it was

    def reached_mm(self, commanded_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the carriage goes for a sequence of commands (mm, in the order sent), and which moved.

        Stick-slip: the carriage follows a command only when it lies at least
        ``dead_band_um`` from where the carriage rests; otherwise it stays
        (2 um commands into a 3 um dead band: 0, 0, 4, 4, 8, ... um). The
        first command is always reached. Returns (reached (K,), moved (K,) bool).
        """
        c = np.atleast_1d(np.asarray(commanded_mm, dtype=float))
        moved = np.ones(c.shape, dtype=bool)
        if not self.dead_band_um > 0 or c.size < 2:
            return c.copy(), moved
        reached, band_mm = c.copy(), 1e-3 * self.dead_band_um
        for i in range(1, c.size):  # a sequence: each stop depends on where the last one left the carriage
            if abs(c[i] - reached[i - 1]) < band_mm - 1e-12:
                reached[i], moved[i] = reached[i - 1], False
        return reached, moved

    def positioning_error_um(self, commanded_mm: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """Systematic positioning error (no noise), shape like ``commanded_mm``."""
        x = np.asarray(commanded_mm, dtype=float)
        d = np.broadcast_to(np.asarray(direction, dtype=float), x.shape)
        e = self.scale_ppm * 1e-6 * x * 1000.0
        if self.periodic_um and self.pitch_mm:
            e = e + self.periodic_um * np.sin(2.0 * np.pi * x / self.pitch_mm + self.periodic_phase_rad)
        return e - 0.5 * self.backlash_um * np.sign(d)

    def true_pose(
        self,
        commanded_mm: np.ndarray,
        direction: np.ndarray,
        rng: np.random.Generator | None = None,
    ) -> TruePose:
        """True carriage pose for commanded positions reached moving in ``direction`` (+1/-1).

        ``rng`` draws the repeatability noise; without it the pose is the
        systematic one (what the stage would do on average).
        """
        x = np.atleast_1d(np.asarray(commanded_mm, dtype=float))
        e_um = self.positioning_error_um(x, direction)
        if rng is not None and self.repeatability_um > 0:
            e_um = e_um + rng.normal(0.0, self.repeatability_um, size=x.shape)
        straight = np.stack([p(x) for p in self.straightness_um], axis=-1)
        angles = np.stack([self.roll_urad(x), self.pitch_urad(x), self.yaw_urad(x)], axis=-1)
        if rng is not None and self.angle_noise_urad > 0:  # drawn after the positions: older seeds stay the same
            angles = angles + rng.normal(0.0, self.angle_noise_urad, size=angles.shape)
        return TruePose(axis_mm=x + e_um * 1e-3, straightness_um=straight, angles_urad=angles)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["straightness_um"] = [asdict(p) for p in self.straightness_um]
        for key in ("roll_urad", "pitch_urad", "yaw_urad"):
            d[key] = asdict(getattr(self, key))
        for p in [*d["straightness_um"], d["roll_urad"], d["pitch_urad"], d["yaw_urad"]]:
            p["poly"] = list(p["poly"])
        if not self.dead_band_um:
            del d["dead_band_um"]  # a stage without one is recorded as before
        if not self.angle_noise_urad:
            del d["angle_noise_urad"]  # the truth records of sessions without it stay as they were
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> "StageErrorModel":
        d = dict(d or {})
        straight = d.pop("straightness_um", None) or [{}, {}]
        angles = {k: ErrorProfile.from_dict(d.pop(k, None)) for k in ("roll_urad", "pitch_urad", "yaw_urad")}
        scalars = {k: float(v) for k, v in d.items() if k in cls.__dataclass_fields__}
        return cls(
            straightness_um=(ErrorProfile.from_dict(straight[0]), ErrorProfile.from_dict(straight[1])),
            **angles,
            **scalars,
        )


@dataclass(frozen=True)
class Vibration:
    """The carriage rings after each move: ``amplitude_um`` * exp(-t / ``decay_s``) * cos(2 pi ``frequency_hz`` t + ``phase_rad``).

    t is the time since the move ended; with phase 0 the first swing is an
    overshoot in the direction of the move. The simulated stage's camera sees
    it; :meth:`settling_time_s` is the truth of the ASME B5.64 settling test.
    """

    amplitude_um: float = 50.0
    frequency_hz: float = 8.0
    decay_s: float = 0.25
    phase_rad: float = 0.0

    def offset_um(self, since_stop_s: Any, direction: Any = 1) -> Any:
        """The ringing (um) ``since_stop_s`` after a move in ``direction`` (+1/-1); 0 before it ended."""
        t = np.asarray(since_stop_s, dtype=float)
        ring = self.amplitude_um * np.exp(-np.maximum(t, 0.0) / self.decay_s) * np.cos(
            2.0 * math.pi * self.frequency_hz * t + self.phase_rad)
        out = np.where(t < 0, 0.0, np.asarray(direction, dtype=float) * ring)
        return float(out) if out.ndim == 0 else out

    def settling_time_s(self, band_um: float) -> float:
        """The last time the ringing is outside +-``band_um`` (0 when it starts inside): the time to settle.

        Sampled finely (1/200 of a period) up to where the envelope is inside
        the band, then refined by bisection on that last crossing.
        """
        if not band_um > 0:
            raise ValueError("settling band must be positive (um)")
        if abs(self.amplitude_um) <= band_um:
            return 0.0
        t_env = self.decay_s * math.log(abs(self.amplitude_um) / band_um)  # the envelope enters the band here
        dt = 1.0 / (200.0 * max(self.frequency_hz, 1e-6))
        t = np.arange(0.0, t_env + dt, dt)
        outside = np.flatnonzero(np.abs(self.offset_um(t)) > band_um)
        if outside.size == 0:
            return 0.0
        lo, hi = float(t[outside[-1]]), float(t[outside[-1]]) + dt
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if abs(self.offset_um(mid)) > band_um else (lo, mid)
        return 0.5 * (lo + hi)

    def to_dict(self) -> dict[str, float]:
        d = {"amplitude_um": self.amplitude_um, "frequency_hz": self.frequency_hz, "decay_s": self.decay_s}
        return {**d, "phase_rad": self.phase_rad} if self.phase_rad else d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Vibration":
        return cls(**{k: float(v) for k, v in d.items() if k in cls.__dataclass_fields__})


@dataclass(frozen=True)
class PlanarTruePose:
    """Where the carriage really is, for K commanded (x, y) positions."""

    plane_mm: np.ndarray  # shape (K, 2): true position in the stage plane
    normal_um: np.ndarray  # shape (K,): out-of-plane displacement
    angles_urad: np.ndarray  # shape (K, 3): rotation about stage x, y and the plane normal


@dataclass(frozen=True)
class PlanarErrorModel:
    """Errors of an XY gantry: one :class:`StageErrorModel` per axis plus squareness."""

    x: StageErrorModel = field(default_factory=StageErrorModel)
    y: StageErrorModel = field(default_factory=StageErrorModel)
    squareness_urad: float = 0.0  # angle between +X and +Y motion minus 90 deg

    def true_pose(self, commanded_mm: np.ndarray, direction: np.ndarray,
                  rng: np.random.Generator | None = None) -> PlanarTruePose:
        """True pose for commanded (x, y) (shape (K, 2)) approached in ``direction`` (K, 2) of +-1."""
        c = np.atleast_2d(np.asarray(commanded_mm, dtype=float))
        d = np.broadcast_to(np.asarray(direction, dtype=float), c.shape)
        px = self.x.true_pose(c[:, 0], d[:, 0], rng)
        py = self.y.true_pose(c[:, 1], d[:, 1], rng)
        g = self.squareness_urad * 1e-6
        # the Y carriage moves along (-sin g, cos g); each axis' in-plane straightness is across its motion
        x_true = px.axis_mm - np.sin(g) * py.axis_mm + 1e-3 * py.straightness_um[:, 0]
        y_true = np.cos(g) * py.axis_mm + 1e-3 * px.straightness_um[:, 0]
        normal = px.straightness_um[:, 1] + py.straightness_um[:, 1]
        # X's roll is about x, Y's about y; pitch of X is about y (its v1 ~ y), of Y about x
        angles = np.stack([px.angles_urad[:, 0] + py.angles_urad[:, 1],
                           px.angles_urad[:, 1] + py.angles_urad[:, 0],
                           px.angles_urad[:, 2] + py.angles_urad[:, 2]], axis=-1)
        return PlanarTruePose(np.stack([x_true, y_true], axis=-1), normal, angles)

    def to_dict(self) -> dict[str, Any]:
        return {"x": self.x.to_dict(), "y": self.y.to_dict(), "squareness_urad": self.squareness_urad}

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> "PlanarErrorModel":
        d = d or {}
        return cls(StageErrorModel.from_dict(d.get("x")), StageErrorModel.from_dict(d.get("y")),
                   float(d.get("squareness_urad", 0.0)))
