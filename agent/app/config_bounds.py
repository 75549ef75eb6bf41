"""The range of every numeric setting, in one table, and the shape of the settings that are addresses.

`agent.app.config` checks each value a file or ``--set`` gives against `BOUNDS` before any part of
the agent sees it, so a value no run could use (``map.resolution=0``, ``bus.query_timeout_s=-1``,
``episode.budget=-5``, NaN or infinity anywhere) is refused with its dotted key instead of failing
later, once a world is up. A tuple or a table of numbers (``map.floor_band``, ``act.min_look``) has
each of its items checked. The ranges are generous: they keep out what cannot work or would only
hang, not what merely looks unusual; the sections' own checks (a map cell a whole number of voxels)
still apply after them. Every numeric setting has an entry (tests/test_config_edges.py holds to
that), so a new one cannot slip in unchecked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from behaviours.approach_storage import MAX_SQUEEZE_M
from worlds.bus.session import check_endpoint

#: The largest seed a world accepts (a signed 64-bit integer); `worlds.commands` refuses larger.
MAX_SEED = 2**63 - 1
_HOUR_S = 3600.0
_DAY_S = 24 * _HOUR_S


@dataclass(frozen=True)
class Range:
    """Numbers from ``low`` to ``high``, each end excluded when its ``*_open`` flag is set.

    Args:
        low: the least value.
        high: the greatest value.
        low_open: whether ``low`` itself is refused.
        high_open: whether ``high`` itself is refused.
    """

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def check(self, name: str, value: Any) -> None:
        """Refuse ``value`` unless it is a finite number in the range.

        Args:
            name: the setting's dotted key, for the message.
            value: the value.

        Raises:
            ValueError: naming the key, the value and the range.
        """
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{name}: {value!r} must be a finite number in {self}")
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        if not (above and below):
            raise ValueError(f"{name}: {value!r} must lie in {self}")

    def __str__(self) -> str:
        return (f"{'(' if self.low_open else '['}{_number(self.low)}, "
                f"{_number(self.high)}{')' if self.high_open else ']'}")


@dataclass(frozen=True)
class Locator:
    """A Zenoh endpoint such as ``tcp/127.0.0.1:7450`` (`worlds.bus.session.check_endpoint`)."""

    def check(self, name: str, value: Any) -> None:
        """Refuse ``value`` unless Zenoh can listen on or connect to it.

        Args:
            name: the setting's dotted key, for the message.
            value: the endpoint.

        Raises:
            ValueError: naming the key and the endpoint.
        """
        try:
            check_endpoint(value)
        except ValueError as error:
            raise ValueError(f"{name}: {error}") from None


def _number(value: float) -> str:
    return str(value) if isinstance(value, int) else f"{value:g}"


def _above(low: float, high: float) -> Range:
    """``(low, high]``: the least value excluded, as for sizes, periods and temperatures."""
    return Range(low, high, low_open=True)


_SHARE = Range(0.0, 1.0)
_METRES = Range(0.0, 100.0)
_HEIGHT_M = Range(-10.0, 10.0)
_LOGIT = Range(-100.0, 100.0)
_BETA = _above(0.0, 1000.0)
_TIMEOUT_S = _above(0.0, _HOUR_S)
_TEMPERATURE = _above(0.0, 100.0)

#: Every numeric setting's range, by dotted key.
BOUNDS: dict[str, Range | Locator] = {
    "camera.width": Range(8, 4096),  # what the world's camera renders (worlds.robot.CameraConfig)
    "camera.height": Range(8, 4096),
    "camera.hfov_deg": Range(10.0, 170.0, low_open=True, high_open=True),
    "bus.listen": Locator(),
    "bus.query_timeout_s": _TIMEOUT_S,
    "bus.move_timeout_s": _TIMEOUT_S,
    "bus.world_start_timeout_s": _TIMEOUT_S,
    "episode.budget": Range(0, 100_000),  # 0: the scenario's own
    "episode.max_seconds": _above(0.0, 7 * _DAY_S),
    "episode.tick_period_s": Range(0.0, 60.0),  # 0: ticks are not paced
    "episode.max_wait_s": _above(0.0, 60.0),
    "episode.vlm_timeout_s": _TIMEOUT_S,
    "ray.cpus_per_episode": _above(0.0, 1024.0),  # Ray takes fractions of a CPU; a node has at most this many
    "ray.cpus_per_agent": _above(0.0, 1024.0),
    "map.size_m": _above(0.0, 1000.0),
    "map.resolution": _above(0.0, 10.0),
    "map.floor_band": _HEIGHT_M,
    "map.obstacle_min_z": _HEIGHT_M,
    "map.obstacle_max_z": _HEIGHT_M,
    "map.surface_tsdf": _above(0.0, 2.0),  # two normalised TSDF values, each within [-1, 1]
    "map.robot_radius": _above(0.0, 5.0),
    "map.near_field_radius": Range(0.0, 10.0),
    "map.driven_radius": Range(0.0, 5.0),
    "map.tsdf.voxel_size": _above(0.0, 1.0),
    "map.tsdf.trunc_voxels": _above(0.0, 100.0),
    "map.tsdf.depth_max": _above(0.0, 100.0),
    "map.tsdf.block_resolution": Range(1, 64),
    "map.tsdf.block_count": Range(1, 1_000_000),
    "explore.max_step_m": _above(0.0, 100.0),
    "explore.min_frontier_distance_m": _METRES,
    "explore.min_frontier_size": Range(1, 100_000),
    "explore.min_unexplored_neighbours": Range(0, 8),  # of a cell's eight
    "explore.comfort_m": Range(0.0, 10.0),
    "explore.obstacle_cost": Range(0.0, 1000.0),
    "explore.choice.distance_cost_per_m": Range(0.0, 100.0),
    "explore.choice.keep_within_m": _METRES,
    "explore.choice.switch_margin": Range(0.0, 100.0),
    "prompt_points.min_distance_m": _METRES,
    "prompt_points.max_distance_m": _above(0.0, 100.0),
    "prompt_points.max_points": Range(1, 26),  # one letter each
    "prompt_points.min_points": Range(0, 26),
    "prompt_points.merge_distance_m": _METRES,
    "prompt_points.floor_z": _HEIGHT_M,
    "prompt_points.depth_tolerance_m": Range(0.0, 10.0),
    "prompt_points.depth_tolerance_frac": _SHARE,
    "semantic_values.tau_lsv": _TEMPERATURE,
    "semantic_values.tau_gsv": _TEMPERATURE,
    "semantic_values.radius_m": _above(0.0, 100.0),
    "semantic_values.sigma_m": _above(0.0, 100.0),
    "frontier_weights.tau_sv": _TEMPERATURE,
    "frontier_weights.tau_sv_normal": _TEMPERATURE,
    "frontier_weights.d_sv_m": _METRES,
    "vlm.sim.seed": Range(0, MAX_SEED),
    "vlm.sim.skill": _SHARE,
    "vlm.sim.notice_area_px": Range(0.0, 1e8),
    "vlm.sim.notice_near_m": _METRES,
    "vlm.sim.notice_distance_m": _METRES,
    "vlm.sim.misread": _SHARE,
    "vlm.sim.room_error": _SHARE,
    "vlm.sim.evidence_logit": _LOGIT,
    "vlm.sim.prior_logit": _LOGIT,
    "vlm.sim.logit_noise": Range(0.0, 100.0),
    "vlm.sim.pad_logit": _LOGIT,
    "vlm.sim.room_view_fraction": _SHARE,
    "vlm.sim.relevance_evidence": _BETA,
    "vlm.sim.relevance_inside": _BETA,
    "vlm.sim.relevance_guess": _BETA,
    "vlm.sim.relevance_none": _BETA,
    "vlm.sim.direction_gain": Range(0.0, 100.0),
    "vlm.sim.mark_window": _SHARE,
    "vlm.openai.timeout_s": _TIMEOUT_S,
    "vlm.openai.retries": Range(0, 100),
    "vlm.openai.backoff_s": Range(0.0, _HOUR_S),
    "vlm.openai.top_logprobs": Range(1, 100),
    "stop.epsilon": Range(0.0, 1.0, low_open=True, high_open=True),
    "stop.entropy_threshold": _above(0.0, 10.0),  # nats; four choices hold at most ln 4
    "stop.relevance_threshold": _SHARE,
    "act.reach_m": _above(0.0, 100.0),
    "act.skill_timeout_s": _TIMEOUT_S,
    "act.min_look": _above(0.0, math.pi),  # rad for doors, m for drawers
    "act.stand.distances_m": _above(0.0, 10.0),
    "act.stand.hinge_shares": _SHARE,
    "act.stand.door_amounts": _above(0.0, math.pi),
    "act.stand.drawer_amounts": _above(0.0, 2.0),
    "act.stand.margin_m": Range(0.0, 1.0),
    "act.stand.max_plans": Range(1, 1000),
    "act.max_parts": Range(1, 100),
    "act.approach.views": Range(1, 100),
    "act.approach.max_moves": Range(1, 1000),
    "act.approach.done_m": _above(0.0, 100.0),
    "act.approach.entered_m": _above(0.0, 100.0),
    "act.approach.room_floor_m": _above(0.0, 100.0),
    "act.approach.squeeze_m": Range(0.0, MAX_SQUEEZE_M),
    "act.approach.sightings.max_depth_m": _above(0.0, 100.0),
    "act.approach.sightings.min_pixels": Range(1, 10_000_000),
    "act.approach.sightings.merge_m": _above(0.0, 100.0),
    "act.approach.viewpoint.distances_m": _above(0.0, 100.0),
    "act.approach.viewpoint.bearings": Range(1, 360),
    "act.approach.viewpoint.own_m": _METRES,
    "act.approach.viewpoint.apart_rad": Range(0.0, math.pi),
}


def check_bounds(name: str, value: Any) -> None:
    """Refuse a setting's value outside its range in `BOUNDS`; each item of a tuple or table is
    checked on its own. Settings without an entry (words, paths, booleans) pass.

    Args:
        name: the setting's dotted key (``map.resolution``).
        value: its value, already of the setting's type.

    Raises:
        ValueError: naming the key (``map.floor_band[1]``, ``act.min_look.door``), the value and
            the range.
    """
    bound = BOUNDS.get(name)
    if bound is None:
        return
    if isinstance(value, tuple):
        for index, item in enumerate(value):
            bound.check(f"{name}[{index}]", item)
    elif isinstance(value, dict):
        for key, item in value.items():
            bound.check(f"{name}.{key}", item)
    else:
        bound.check(name, value)
