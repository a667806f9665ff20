"""What a simulated experiment is: the rig, the plan, the noise and the injected outliers (one or two axes).

Its own module so that the presets of :mod:`lps_gui.core.truth.simulate` and of
:mod:`lps_gui.core.planning.target_presets` (rows of targets) build it without
importing each other; :mod:`lps_gui.core.truth.simulate` re-exports it.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from lps_gui.core.geometry.board import Board
from lps_gui.core.geometry.target_rig import TargetLayout
from lps_gui.core.planning.plan import Plan
from lps_gui.core.truth.realism import Realism, printed_rng
from lps_gui.core.truth.rig import Rig
from lps_gui.core.truth.stage_errors import Vibration

RECAPTURE_STREAM = 36  # printed_rng's 35's neighbour: one seed's streams are told apart by such a tag


def recapture_seed(seed: int) -> int:
    """The seed of a re-capture of the session of ``seed``: a 32-bit word of ``seed``'s own stream, so it replays
    no other session's draws (seed + 1 would be the next seed's)."""
    return int(np.random.SeedSequence([int(seed), RECAPTURE_STREAM]).generate_state(1)[0])


@dataclass(frozen=True)
class SimulationSpec:
    """A simulated experiment; every random draw comes from ``seed``."""

    name: str
    rig: Rig  # as many axes as the plan
    plan: Plan
    noise_px: float = 0.1
    noise_clip_px: float | None = None  # paper's synthetic case: |noise| < 1 px
    missing_fraction: float = 0.0
    replaced_views: tuple[int, ...] = ()  # images swapped for another position's
    replaced_offset: int = 37  # ... the one this many captures away
    bumped_views: tuple[int, ...] = ()  # camera knocked: rotated by bump_mrad
    bump_mrad: float = 3.0
    seed: int = 0
    vibration: Vibration | None = None  # the carriage rings after each move (ASME B5.64 settling test)
    frame_interval_s: float = 0.01  # time between the frames of a stop (the camera's exposure), s
    layout: TargetLayout | None = None  # a row or constellation of targets (SPEC 13); the rig's board is its first
    realism: Realism | None = None  # lens misfit, prints off scale and bowed, blur and noise over the image (issue 35)
    print_seed: int | None = None  # whose prints the board is (a re-capture keeps the board it was made with); None: seed

    @property
    def stitched(self) -> bool:
        """One board moved between the plan's segments (SPEC 13): the layout holds its placements (one board, the
        same markers), one seen at a time (segment k's views see target k only). A row of distinct targets
        captured with a segmented plan stays a row."""
        if self.layout is None or self.plan.segments is None:
            return False
        same_board = len({(t.board, t.first_marker) for t in self.layout.targets}) == 1
        return same_board and len(self.layout.targets) == len(self.plan.segments)

    @property
    def one_board(self) -> bool:
        """The camera sees one board: no layout, or a stitched session's placements of the one board."""
        return self.layout is None or self.stitched

    def printed(self) -> Board | TargetLayout:
        """The board (or layout) as the camera sees it: as printed with realism on, else the nominal one; a stitched
        session's one board is one print, whatever its placement."""
        scene = self.rig.board if self.one_board else self.layout
        if self.realism is None:
            return scene
        rng = printed_rng(self.seed if self.print_seed is None else self.print_seed)
        return self.realism.printed_board(scene, rng) if isinstance(scene, Board) else self.realism.printed_layout(scene, rng)

    def recaptured(self) -> SimulationSpec:
        """The same rig captured again (the compensated as-left pass): the same stage, board and prints, its own
        image noise and repeatability draws, a stream of this seed independent of every other seed's (seed + 1
        would replay the next seed's session draw for draw)."""
        return replace(self, seed=recapture_seed(self.seed),
                       print_seed=self.seed if self.print_seed is None else self.print_seed)

    def camera_realism(self) -> dict[str, Any]:
        """What the simulated camera and renderers take for the realism: ``lens``, ``printed`` and Lighting fields."""
        if self.realism is None:
            return {}
        return {"lens": self.realism.lens(self.rig.intrinsics), "printed": self.printed(), **self.realism.lighting()}

    def realism_truth(self) -> dict[str, Any]:
        """session.json ``truth.realism``: the switches, the true lens's extra terms and each print's scale and bow."""
        if self.realism is None:
            return {}
        scene = self.printed()
        boards = [scene] if isinstance(scene, Board) else [t.board for t in scene.targets]
        return {"realism": {**self.realism.to_dict(), "lens": self.realism.lens(self.rig.intrinsics).to_dict(),
                            "printed": [{"square_mm": b.square_mm, "warp_mm": list(b.warp_mm or (0.0, 0.0))}
                                        for b in boards]}}
