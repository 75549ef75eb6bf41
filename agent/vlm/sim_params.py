"""The simulated VLM's parameters: how well it sees, reads, tells rooms apart, and how it answers.

Each is a setting (`[vlm.sim]`, `--set vlm.sim.NAME=VALUE`); docs/vlm-sim.md says what each does
and what the defaults measure on rendered frames. A calibration file records them all, since every
one of them changes the scores conformal prediction is calibrated on.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SimParams:
    """The simulator's accuracy and miscalibration. Defaults give a capable but fallible model."""

    seed: int = 0
    skill: float = 0.98
    notice_area_px: float = 40.0
    notice_near_m: float = 3.0
    notice_distance_m: float = 8.0
    misread: float = 0.05
    room_error: float = 0.1
    evidence_logit: float = 4.0
    prior_logit: float = 2.5
    logit_noise: float = 0.6
    pad_logit: float = -6.0
    room_view_fraction: float = 0.12
    relevance_evidence: tuple[float, float] = (12.0, 2.0)
    relevance_inside: tuple[float, float] = (16.0, 1.5)
    relevance_guess: tuple[float, float] = (4.0, 4.0)
    relevance_none: tuple[float, float] = (1.5, 8.0)
    direction_gain: float = 4.0
    mark_window: float = 0.15  # half-size of the region around a letter, as a share of the image width

    def __post_init__(self) -> None:
        for name in ("skill", "misread", "room_error", "room_view_fraction", "mark_window"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"vlm.sim.{name}: {value} must lie in [0, 1]")
        for name in ("notice_area_px", "notice_distance_m", "logit_noise", "direction_gain"):
            if getattr(self, name) < 0:
                raise ValueError(f"vlm.sim.{name}: must not be negative")
        for name in ("relevance_evidence", "relevance_inside", "relevance_guess", "relevance_none"):
            shape = getattr(self, name)
            if len(shape) != 2 or not all(v > 0 for v in shape):
                raise ValueError(f"vlm.sim.{name}: {shape!r} must be two positive Beta shape parameters")
