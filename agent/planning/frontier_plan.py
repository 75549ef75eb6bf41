"""Choosing where to go next: frontiers reachable from the robot, and a path to one of them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from agent.mapping.occupancy import ExplorationMap
from agent.planning.explore_method import ExploreMethod, ExploreStrategy
from agent.planning.frontier_choice import FrontierChoiceConfig
from agent.planning.frontier import Frontier, cluster_frontiers, frontier_cells
from agent.planning.map_fields import MapFields
from agent.planning.paths import DistanceField, simplify_path, truncate_path


@dataclass(frozen=True)
class ExploreConfig:
    method: str = "semantic"  # fbe, semantic, semantic-no-lsv, semantic-no-gsv or lfe (agent.planning.explore_method)
    max_step_m: float = 3.0  # path length the robot may drive between two observations
    min_frontier_distance_m: float = 0.5  # nearer frontiers are where the robot already stands
    min_frontier_size: int = 3
    min_unexplored_neighbours: int = 2
    comfort_m: float = 0.3  # beyond the robot's radius, clearance that paths prefer to keep
    obstacle_cost: float = 3.0  # extra cost per metre right at the robot's radius from an obstacle
    choice: FrontierChoiceConfig = field(default_factory=FrontierChoiceConfig)  # which frontier to head for

    def __post_init__(self) -> None:
        if self.method not in set(ExploreMethod):
            raise ValueError(f"explore.method: {self.method!r} is not one of {', '.join(ExploreMethod)}")

    @cached_property
    def strategy(self) -> ExploreStrategy:
        """What ``method`` means, made once for this configuration; everything that depends on the
        method asks this."""
        return ExploreStrategy.of(self.method)


@dataclass(frozen=True)
class Candidates:
    """The frontiers the robot can reach now, with the path lengths to their centres."""

    frontiers: list[Frontier]
    distances_m: np.ndarray
    field: DistanceField
    traversable: np.ndarray  # the cells the field was computed over


@dataclass(frozen=True)
class MovePlan:
    """One step: the waypoints to drive (world x, y), the heading at the end, and why: the frontier
    it heads for (None for a move towards something else, a view of storage, say) and the length
    of the whole path to its goal."""

    path_xy: np.ndarray
    yaw: float
    frontier: Frontier | None
    goal_distance_m: float


def reachable_frontiers(world_map: ExplorationMap, robot_xy: tuple[float, float],
                        config: ExploreConfig = ExploreConfig(), fields: MapFields | None = None) -> Candidates:
    """Frontier clusters in the free space connected to the robot, nearer ones dropped.

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands (world x, y).
        config: the exploration settings.
        fields: the map's fields shared with other planners this step (computed afresh without).

    Returns:
        The frontiers, their path lengths and the field they were measured over.
    """
    fields = MapFields() if fields is None else fields
    field, traversable = fields.drive_field(world_map, robot_xy, config)
    reachable = np.isfinite(field.metres)
    mask = frontier_cells(reachable, world_map.explored, world_map.occupied, config.min_unexplored_neighbours)
    frontiers = cluster_frontiers(world_map.spec, mask, world_map.explored, world_map.occupied, config.min_frontier_size)
    distances = np.array([field.metres[f.centre] for f in frontiers])
    keep = distances >= config.min_frontier_distance_m
    return Candidates([f for f, k in zip(frontiers, keep) if k], distances[keep], field, traversable)


def plan_move(candidates: Candidates, index: int, robot_xy: tuple[float, float],
              config: ExploreConfig = ExploreConfig()) -> MovePlan:
    """A path toward frontier ``index``, cut to one step, ending with the heading of the frontier normal.

    Args:
        candidates: the frontiers and the distance field from the robot.
        index: the chosen frontier.
        robot_xy: where the robot stands.
        config: the step's length and the path's settings.

    Returns:
        The move.
    """
    frontier = candidates.frontiers[index]
    robot_xy = np.asarray(robot_xy, dtype=float)
    field = candidates.field
    cells = field.path_to(frontier.centre)
    # Start where the robot is, not at its cell's centre: a robot touching an obstacle must not take
    # a first sideways step toward it.
    waypoints = np.vstack([robot_xy, field.spec.to_world(cells[1:])]) if len(cells) > 1 else np.array([robot_xy])
    full = simplify_path(waypoints)
    path = truncate_path(full, config.max_step_m)
    heading = frontier.normal  # look into the unexplored space beyond the frontier
    return MovePlan(path, math.atan2(heading[1], heading[0]), frontier, float(candidates.distances_m[index]))
