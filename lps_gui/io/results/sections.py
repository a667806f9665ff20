"""The sections of results.json (docs/ARCHITECTURE.md) as typed, frozen dataclasses: what readers name.

Each field is a key the report, GUI, CLI or pipeline reads; every other key
stays in the section's ``raw`` (:class:`lps_gui.io.results.typed_json.Section`). The
document itself is :class:`lps_gui.io.results.model.Results`.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lps_gui.io.results.typed_json import Section, finite_number


@dataclass(frozen=True, kw_only=True)
class Software(Section):
    name: str | None = None
    version: str | None = None


@dataclass(frozen=True, kw_only=True)
class Inputs(Section):
    """What the estimate read: the session folder, the hashes of its files, where the intrinsics came from."""

    session: str | None = None
    intrinsics_source: str | None = None
    sha256: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class BoardRecord(Section):
    """The board as the estimate used it (``square_mm`` nominal at 20 C; ``environment.square_mm_used``)."""

    type: str | None = None
    inner_corners: tuple[int, ...] = ()
    square_mm: float | None = None


@dataclass(frozen=True, kw_only=True)
class IntrinsicsRecord(Section):
    """The camera intrinsics the estimate used, with their 1-sigma (``std``, by name) when known."""

    image_size: tuple[int, ...] = ()
    camera_matrix: tuple[tuple[float, ...], ...] = ()
    dist: tuple[float, ...] = ()
    std: Mapping[str, float | None] = field(default_factory=dict)
    rms_px: float | None = None
    n_views: int | None = None

    @property
    def K(self) -> np.ndarray:
        """The camera matrix, shape (3, 3); the identity when the record has none."""
        return np.asarray(self.camera_matrix, dtype=float) if self.camera_matrix else np.eye(3)


@dataclass(frozen=True, kw_only=True)
class Parameters(Section):
    """The fit: its statistics (the stage line's vectors stay in ``raw``: R_cam_board, l0_cam_mm, n_cam, ...)."""

    open_keys = True

    sigma_px: float | None = None
    rms_px: float | None = None
    n_views: int | None = None
    n_used: int | None = None
    n_outliers: int | None = None
    n_observations: int | None = None
    dof: int | None = None
    iterations: int | None = None
    converged: bool | None = None
    reference_index: int | None = None


@dataclass(frozen=True, kw_only=True)
class Position(Section):
    """One capture's row: identity and flags typed; measured columns by name (:meth:`Section.number`)."""

    open_keys = True

    index: int
    run: int | None = None
    direction: str = "+"
    outlier: bool = False
    outlier_reason: str | None = None
    used: bool | None = None
    file: str | None = None

    @property
    def usable(self) -> bool:
        """The estimate used this view (``used``; older files: not an outlier)."""
        return self.used if self.used is not None else not self.outlier


@dataclass(frozen=True, kw_only=True)
class Flag(Section):
    """A finding about one view (``index``) or the session (None): an outlier of round ``round``, a lens misfit."""

    index: int | None = None
    kind: str | None = None
    message: str | None = None
    round: int | None = None


@dataclass(frozen=True, kw_only=True)
class Spectrum(Section):
    period_mm: tuple[float | None, ...] = ()
    amplitude_um: tuple[float | None, ...] = ()
    method: str | None = None


@dataclass(frozen=True, kw_only=True)
class SingleRun(Section):
    """``figures.single_run``: the figures of all captures as one run (SPEC 5)."""

    n_captures: int | None = None
    mean_step_mm: float | None = None
    step_std_um: float | None = None
    max_abs_deviation_um: float | None = None
    max_abs_deviation_noise: Mapping[str, Any] | None = None  # measured, bias, u_noise, corrected (extreme_noise)
    deviation_span_um: float | None = None
    scale_ppm: float | None = None
    scale_sigma_ppm: float | None = None
    scale_sigma_total_ppm: float | None = None
    periodic_amplitude_um: float | None = None
    periodic_period_mm: float | None = None
    spectrum: Spectrum | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class Iso230(Section):
    """``figures.iso230_2``: E/M/B/R/A by name (``get("A_um")``; an open set), per-target table, notes."""

    open_keys = True

    n_targets: int | None = None
    n_runs_up: int | None = None
    n_runs_down: int | None = None
    per_target: Mapping[str, Any] | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class SpanResolution(Section):
    """A peak-to-valley over the targets and what noise alone would span (core/metrology/resolution.py)."""

    span_um: float | None = None
    sigma_um: float | None = None
    noise_span_um: float | None = None
    n_targets: int | None = None
    resolved: bool | None = None
    measured_span_um: float | None = None  # before the noise's selection is taken out (span_um: after)
    u_span_um: float | None = None  # span_um's standard uncertainty (core/metrology/extreme_noise.py)
    u_model_um: float | None = None  # the constant-orientation model's share (pipeline/results/board_plane.py)


@dataclass(frozen=True, kw_only=True)
class Straightness(Section):
    basis: str | None = None
    v1: SpanResolution | None = None
    v2: SpanResolution | None = None


@dataclass(frozen=True, kw_only=True)
class ImageRotation(Section):
    span_urad: float | None = None
    sigma_urad: float | None = None
    noise_span_urad: float | None = None
    n_targets: int | None = None
    resolved: bool | None = None
    measured_span_urad: float | None = None
    u_span_urad: float | None = None


@dataclass(frozen=True, kw_only=True)
class AngleResolution(Section):
    max_abs_urad: float | None = None  # the noise's selection taken out (core/metrology/extreme_noise.py)
    measured_max_abs_urad: float | None = None
    u_max_abs_urad: float | None = None
    noise_max_abs_urad: float | None = None
    resolved: bool | None = None


@dataclass(frozen=True, kw_only=True)
class PlanarNode(Section):
    """One grid node of the planar error map: mean error vector (um) at its target (mm)."""

    target_mm: tuple[float, ...] = ()
    n: int | None = None
    error_um: tuple[float | None, ...] | None = None
    sigma_um: Any = None
    truth_error_um: tuple[float | None, ...] | None = None


@dataclass(frozen=True, kw_only=True)
class Figures(Section):
    """``figures``: single-run, per-run, ISO 230-2, straightness and angle figures; ``planar`` for SPEC 10."""

    single_run: SingleRun | None = None
    per_run: tuple[Any, ...] = ()
    iso230_2: Iso230 | None = None
    straightness_um_max: float | None = None
    straightness_span_um: tuple[float | None, ...] = ()
    straightness_sigma_um: float | None = None
    straightness: Straightness | None = None
    image_rotation: ImageRotation | None = None
    angles_resolution: Mapping[str, AngleResolution] = field(default_factory=dict)
    angles_span_urad: Mapping[str, float | None] = field(default_factory=dict)
    planar: PlanarFigures | None = None


@dataclass(frozen=True, kw_only=True)
class PlanarAxis(Section):
    """``figures.planar.per_axis[X|Y]``: the worst line's straightness and ISO 230-2 block of one axis."""

    lines: int | None = None
    straightness_um_max: float | None = None
    straightness_sigma_um: float | None = None
    straightness: SpanResolution | None = None
    out_of_plane: SpanResolution | None = None
    iso230_2: Figures | None = None  # that axis's figures shaped like a line session's ``figures``


@dataclass(frozen=True, kw_only=True)
class PlanarFigures(Section):
    """``figures.planar`` (SPEC 10): squareness, per-axis scales, the axes' figures, the grid's nodes."""

    squareness_urad: float | None = None
    squareness_sigma_urad: float | None = None
    squareness_um_per_m: float | None = None
    scale_x_ppm: float | None = None
    scale_x_sigma_ppm: float | None = None
    scale_y_ppm: float | None = None
    scale_y_sigma_ppm: float | None = None
    per_axis: Mapping[str, PlanarAxis] = field(default_factory=dict)
    lines: tuple[Any, ...] = ()
    nodes: tuple[PlanarNode, ...] = ()
    notes: tuple[str, ...] = ()
    motion_matrix: tuple[tuple[float, ...], ...] = ()  # G: the stage's axes in the board frame (SPEC 10)


@dataclass(frozen=True, kw_only=True)
class TruthComparison(Section):
    """``truth_comparison`` (simulated sessions): the estimate against the simulator's truth.

    An open set of figures (:meth:`numbers`); those that readers name are typed.
    """

    open_keys = True

    position_rms_error_um: float | None = None
    position_max_abs_error_um: float | None = None
    mean_sigma_um: float | None = None
    median_sigma_um: float | None = None
    z_mean_square: float | None = None
    injected_outliers: tuple[Any, ...] = ()
    flagged_outliers: tuple[Any, ...] = ()
    board_plane_rms_error_um: float | None = None
    board_plane_z_mean_square: float | None = None
    abbe_rms_um: float | None = None
    reference: str | None = None  # planar: the frame the errors are taken in
    per_coordinate_rms_error_um: tuple[float | None, ...] | None = None
    squareness_urad: float | None = None
    squareness_error_urad: float | None = None
    squareness_z: float | None = None
    scale_x_error_ppm: float | None = None
    scale_y_error_ppm: float | None = None
    out_of_plane_rms_error_um: float | None = None
    out_of_plane_z_mean_square: float | None = None
    targets: TargetsTruth | None = None  # a row's or constellation's target poses (SPEC 13)

    def numbers(self) -> list[tuple[str, float]]:
        """(key, value) of every finite numeric figure, in the document's order."""
        return [(k, v) for k, v in ((k, finite_number(v)) for k, v in self.raw.items()) if v is not None]


@dataclass(frozen=True, kw_only=True)
class TargetTruth(Section):
    """One target's pose against the simulator's: the errors and the largest |error| / sigma (None for target 0)."""

    id: str | None = None
    rvec_error_rad: tuple[float | None, ...] = ()
    p_error_mm: tuple[float | None, ...] = ()
    max_abs_z: float | None = None


@dataclass(frozen=True, kw_only=True)
class TargetsTruth(Section):
    """``truth_comparison.targets``: every target's pose against the truth, the worst |error| / sigma."""

    per_target: tuple[TargetTruth, ...] = ()
    max_abs_z: float | None = None
    z_mean_square: float | None = None


@dataclass(frozen=True, kw_only=True)
class EnvironmentRecord(Section):
    """``environment``: the temperatures and coefficients recorded, and the thermal correction applied."""

    board_temperature_c: float | None = None
    board_cte_ppm_per_k: float | None = None
    square_mm_uncertainty_um: float | None = None
    stage_temperature_c: float | None = None
    stage_cte_ppm_per_k: float | None = None
    temperature_uncertainty_k: float | None = None
    notes: str | None = None
    reference_temperature_c: float | None = None
    board_scale_correction_ppm: float | None = None
    square_mm_nominal: float | None = None
    square_mm_used: float | None = None


@dataclass(frozen=True, kw_only=True)
class BudgetRow(Section):
    """One source of the GUM budget (core/metrology/uncertainty_budget.py)."""

    source: str
    type: str | None = None
    value: float | None = None
    unit: str | None = None
    sensitivity: float | None = None
    contribution_um: float | None = None
    note: str | None = None


@dataclass(frozen=True, kw_only=True)
class Uncertainty(Section):
    """``uncertainty``: the budget, U (k = 2) of every figure; a planar session's in ``per_axis``."""

    budget: tuple[BudgetRow, ...] = ()
    combined_standard_um: float | None = None
    coverage_factor: float | None = None
    expanded_k2_um: float | None = None
    noise_standard_um: float | None = None
    not_in_u: tuple[str, ...] = ()
    applies_to: str | None = None
    travel_mm: float | None = None
    figures_k2: Mapping[str, float | None] = field(default_factory=dict)
    per_axis: Mapping[str, Uncertainty] = field(default_factory=dict)

    def u_k2(self, key: str) -> float | None:
        """U (k = 2) of the figure ``key`` of ``figures_k2``, None when not assessed."""
        return finite_number(self.figures_k2.get(key))


@dataclass(frozen=True, kw_only=True)
class AsmeFigure(Section):
    """One ISO 230-2 figure under both names (``asme_b5_64.figures``, docs/asme-b5.64.md)."""

    symbol: str | None = None
    key: str | None = None
    iso230_2: str | None = None
    asme_b5_64: str | None = None
    value_um: float | None = None
    U_um: float | None = None


@dataclass(frozen=True, kw_only=True)
class UncertaintyRatio(Section):
    """Tolerance over U (k = 2) of one specified figure; ``tur`` None without U."""

    figure: str | None = None
    quantity: str | None = None
    tolerance: float | None = None
    U: float | None = None
    unit: str | None = None
    tur: float | None = None


@dataclass(frozen=True, kw_only=True)
class AsmeB564(Section):
    """``asme_b5_64``: the figures named both ways, the TURs and an ASME test's own section (steps, settling)."""

    figures: tuple[AsmeFigure, ...] = ()
    test_uncertainty_ratio: tuple[UncertaintyRatio, ...] = ()
    incremental_step: IncrementalStep | None = None  # asme_test min-step only
    settling: Settling | None = None  # asme_test settling only

    @property
    def tests_run(self) -> tuple[IncrementalStep | Settling, ...]:
        """The sections of the tests the session ran, incremental step first (not just the names of the figures)."""
        return tuple(t for t in (self.incremental_step, self.settling) if t is not None and t.raw)

    @property
    def has_test(self) -> bool:
        """The session ran the incremental-step or the settling test."""
        return bool(self.tests_run)


# ----------------------------------------------------------------------------- SPEC 13: targets


@dataclass(frozen=True, kw_only=True)
class TargetRecord(Section):
    """One target of a row or constellation (results.json ``targets``, docs/targets.md); target 0 is the world frame.

    ``stretch_mm`` is [first, last] stop that saw it, each (x,) on a line or (x, y) on a plane; a
    stitched session's placements carry ``stitch_ties``.
    """

    id: str | None = None
    first_marker: int | None = None
    rvec_rad: tuple[float | None, ...] = ()
    rvec_sigma_rad: tuple[float | None, ...] = ()
    p_mm: tuple[float | None, ...] = ()
    p_sigma_mm: tuple[float | None, ...] = ()
    views: int | None = None
    ties: int | None = None
    stitch_ties: int | None = None
    seen_by: tuple[int, ...] = ()
    tied_by: tuple[int, ...] = ()
    stretch_mm: tuple[tuple[float | None, ...] | None, ...] = ()
    square_mm: float | None = None
    square_mm_uncertainty_um: float | None = None
    scale_ppm: float | None = None
    covered_fraction: float | None = None

    @property
    def stretch(self) -> tuple[tuple[float | None, ...], tuple[float | None, ...]] | None:
        """(first, last) stop that saw the target, None when it was never seen."""
        s = self.stretch_mm
        return (s[0], s[1]) if len(s) == 2 and s[0] and s[1] else None


# ----------------------------------------------------------------------------- SPEC 14: error motions


@dataclass(frozen=True, kw_only=True)
class Motion(Section):
    """One error motion over the stops (``error_motions.motions[EXX]``): values and sigmas relative to the first stop.

    The profile's span keys carry the unit (``span_um`` / ``span_urad``): :meth:`span`, :meth:`noise_span`.
    """

    motion: str | None = None
    unit: str | None = None
    along: str | None = None  # a plane's: the axis whose positions it runs over
    positions_mm: tuple[float | None, ...] | None = None  # a plane's: its own axis' positions
    values: tuple[float | None, ...] = ()
    sigma: tuple[float | None, ...] = ()
    centred_sigma: tuple[float | None, ...] = ()
    median_centred_sigma: float | None = None
    n_targets: int | None = None
    resolved: bool | None = None
    single_view_sigma: tuple[float | None, ...] = ()

    def span(self) -> float | None:
        """The p-v over the targets, in ``unit``."""
        return self.number(f"span_{self.unit}")

    def noise_span(self) -> float | None:
        """The p-v noise alone would give, in ``unit``."""
        return self.number(f"noise_span_{self.unit}")


@dataclass(frozen=True, kw_only=True)
class ToolPoint(Section):
    """``error_motions.tool_point``: the positioning error at the user's tool point and the Abbe term."""

    offset_mm: tuple[float, ...] = ()
    frame: str | None = None
    offset_cam_mm: tuple[float, ...] = ()
    positioning_um: tuple[float | None, ...] = ()
    sigma_um: tuple[float | None, ...] = ()
    abbe_um: tuple[float | None, ...] = ()
    max_abs_abbe_um: float | None = None


@dataclass(frozen=True, kw_only=True)
class MotionTruth(Section):
    """A simulated session's true motion and the estimate's error against it."""

    true_values: tuple[float | None, ...] = ()
    rms_error_urad: float | None = None
    z_mean_square: float | None = None


@dataclass(frozen=True, kw_only=True)
class ErrorMotions(Section):
    """``error_motions`` (SPEC 14, docs/error-motions.md): six motions per axis, by ISO 230-1 name, in SPEC 14's order."""

    basis: str | None = None
    axis: str | None = None  # a line's
    axes: tuple[str, ...] = ()  # a plane's: ("X", "Y"), twelve motions
    reference_index: int | None = None
    frame_world: tuple[tuple[float, ...], ...] = ()
    motions: Mapping[str, Motion] = field(default_factory=dict)
    resolved: Mapping[str, bool | None] = field(default_factory=dict)
    tool_point: ToolPoint | None = None
    truth: Mapping[str, MotionTruth] = field(default_factory=dict)
    lens_model: Mapping[str, Any] | None = None  # the two witnesses of a lens the model cannot follow

    @property
    def axis_names(self) -> tuple[str, ...]:
        """The stage axes the motions are of: a plane's two, else the line's one."""
        return self.axes or (self.axis or "X",)

    def is_resolved(self, iso: str) -> bool:
        """The motion ``iso`` differs from zero beyond noise."""
        return bool(self.resolved.get(iso))


# ----------------------------------------------------------------------------- ASME B5.64 tests


@dataclass(frozen=True, kw_only=True)
class StepSize(Section):
    """One commanded step size of the incremental-step test."""

    commanded_um: float | None = None
    n_steps: int = 0
    n_resolved: int = 0
    n_achieved: int = 0
    n_stuck: int = 0
    n_stuck_by_noise: float | None = None
    sticks: bool = False
    scatter_z2: float | None = None
    mean_achieved_um: float | None = None
    all_achieved: bool | None = None


@dataclass(frozen=True, kw_only=True)
class Step(Section):
    """One step between two stop means: what it achieved and its sigma."""

    commanded_um: float
    achieved_um: float
    sigma_um: float
    resolved: bool | None = None
    achieved: bool | None = None
    stuck: bool = False
    from_mm: float | None = None
    to_mm: float | None = None
    direction: str = "+"


@dataclass(frozen=True, kw_only=True)
class StepTruth(Section):
    dead_band_um: float | None = None


@dataclass(frozen=True, kw_only=True)
class IncrementalStep(Section):
    """``asme_b5_64.incremental_step``: the minimum-incremental-motion test's figures, per size and per step."""

    n_steps: int = 0
    n_resolved: int = 0
    n_achieved: int = 0
    n_stuck: int = 0
    sticks: bool = False
    tolerance: float | None = None
    max_step_sigma_um: float | None = None
    median_step_sigma_um: float | None = None
    minimum_incremental_motion_um: float | None = None
    frames_per_stop: int | None = None
    planned_step_um: float | None = None
    sizes: tuple[StepSize, ...] = ()
    steps: tuple[Step, ...] = ()
    truth: StepTruth | None = None


@dataclass(frozen=True, kw_only=True)
class SettlingStop(Section):
    """One move of the settling test: its frames from rest along the move and the damped-cosine fit."""

    target_mm: float
    direction: str = "+"
    since_move_s: tuple[float | None, ...] = ()
    position_um: tuple[float | None, ...] = ()
    settling_time_s: float | None = None
    settling_time_U_s: float | None = None
    settling_time_frames_s: float | None = None
    rest_um: float | None = None
    amplitude_um: float | None = None
    decay_s: float | None = None
    frequency_hz: float | None = None
    phase_rad: float | None = None
    sigmas: Mapping[str, Any] = field(default_factory=dict)
    residual_sigma_um: float | None = None
    n_frames: int | None = None
    record_s: float | None = None
    frame_interval_s: float | None = None
    band_um: float | None = None


@dataclass(frozen=True, kw_only=True)
class SettlingTruth(Section):
    amplitude_um: float | None = None
    frequency_hz: float | None = None
    decay_s: float | None = None
    settling_time_s: float | None = None


@dataclass(frozen=True, kw_only=True)
class Settling(Section):
    """``asme_b5_64.settling``: the settling time (the longest over the moves) and each move's fit."""

    band_um: float | None = None
    n_stops: int | None = None
    settling_time_s: float | None = None
    settling_time_U_s: float | None = None
    settling_time_frames_s: float | None = None
    median_settling_time_s: float | None = None
    stops: tuple[SettlingStop, ...] = ()
    truth: SettlingTruth | None = None
