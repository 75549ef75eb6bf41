"""The terms of the coverage task (`agent.lfe.coverage`): its numbers, the ground truth, what a
chooser sees and what a run returns.

The simulator reads the ground truth (`TrueHome`) to sense and to stop the robot at obstacles;
the chooser sees only the partial map (`Situation`) and answers with the index of a frontier
(`FrontierChooser`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from agent.mapping.grid import GridSpec
from agent.planning.frontier import Frontier
from worlds.freespace import free_space
from worlds.home import HomeSpec
from worlds.robot import ROBOT_RADIUS

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class CoverageConfig:
    """The coverage task's numbers: the paper's where it gives them.

    ``sensor_range_m`` is 5 m, the depth cut-off of the authors' Habitat configuration; at 0.05 m
    cells a 360° scan then sees up to ~78 m² from one pose. ``robot_radius_m`` is the repo's robot
    (`worlds.robot.ROBOT_RADIUS`, also the EQA map's radius), for which the home generator
    guarantees that every room is reachable through its 0.9–1.1 m doorways.

    Args:
        resolution: map cells (m), the paper's.
        sensor_range_m: how far the panoramic sensor sees (m).
        forward_m: the length of a forward move (m).
        turn_deg: the angle of a turn (degrees, at most 180).
        budget_steps: primitive actions per exploration.
        robot_radius_m: the robot's radius (m).
        replan_every: steps between frontier choices; sooner on arrival or when the goal is no frontier.
        min_frontier_size: cells of the smallest frontier offered.

    Raises:
        ValueError: a number that is not positive, a turn over 180° or a range under one cell.
    """

    resolution: float = 0.05
    sensor_range_m: float = 5.0
    forward_m: float = 0.25
    turn_deg: float = 30.0
    budget_steps: int = 500
    robot_radius_m: float = ROBOT_RADIUS
    replan_every: int = 5
    min_frontier_size: int = 3

    def __post_init__(self) -> None:
        for name in ("resolution", "sensor_range_m", "forward_m", "turn_deg", "robot_radius_m"):
            value = getattr(self, name)
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (number and math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: must be a positive number, got {value!r}")
        for name in ("budget_steps", "replan_every", "min_frontier_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise ValueError(f"{name}: must be a positive integer, got {value!r}")
        if self.turn_deg > 180:
            raise ValueError(f"turn_deg: must be at most 180, got {self.turn_deg!r}")
        if self.sensor_range_m < self.resolution:
            raise ValueError(f"sensor_range_m: must be at least one cell ({self.resolution:g} m), "
                             f"got {self.sensor_range_m!r}")


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class TrueHome:
    """Ground truth of one home on the grid: what the simulator and the oracle may read, never a chooser.

    Args:
        spec: the grid.
        free: bool, floor cells not covered by an obstacle, in the region reachable from the start
            (the coverage denominator).
        occupied: bool, what blocks the sensor's rays (walls, furniture, floor objects); outside
            the grid counts too.
        start_xy: where the robot starts (m).
        start_yaw: the robot's heading at the start (rad).

    Raises:
        ValueError: masks of the wrong kind or shape, overlapping or empty, or a start off the free floor.
    """

    spec: GridSpec
    free: np.ndarray
    occupied: np.ndarray
    start_xy: tuple[float, float]
    start_yaw: float

    def __post_init__(self) -> None:
        for name in ("free", "occupied"):
            mask = getattr(self, name)
            if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.shape != self.spec.shape:
                raise ValueError(f"{name}: must be a bool mask of the grid's shape {self.spec.shape}, got "
                                 f"{getattr(mask, 'dtype', type(mask).__name__)} {getattr(mask, 'shape', '')}")
        if (self.free & self.occupied).any():
            raise ValueError("free: overlaps occupied")
        if not self.free.any():
            raise ValueError("free: has no cell")
        cell = self.spec.to_cell(np.asarray(self.start_xy, dtype=float))
        if not (self.spec.inside(cell) and self.free[cell[0], cell[1]]):
            raise ValueError(f"start_xy: {self.start_xy} is not on a free cell")
        if not math.isfinite(self.start_yaw):
            raise ValueError(f"start_yaw: must be finite, got {self.start_yaw!r}")

    @classmethod
    def from_home(cls, home: HomeSpec, config: CoverageConfig = CoverageConfig(), seed: int = 0) -> TrueHome:
        """Rasterise ``home`` (`worlds.freespace`) and draw a start pose from ``seed``.

        The start is a cell where the robot fits, in the free-space component that reaches the most
        rooms; the heading is uniform. Free floor is then the floor connected to the start: a
        pocket no ray can ever enter would otherwise count against every method alike.

        Args:
            home: the generated home.
            config: its resolution and the robot's radius are used.
            seed: draws the start cell and heading.

        Returns:
            The home's ground truth.

        Raises:
            ValueError: nowhere in the home for the robot to stand.
        """
        space = free_space(home, config.robot_radius_m, config.resolution)
        occupied = space.clearance_m == 0
        main = space.main_component()
        if main == 0:
            raise ValueError(f"home {home.seed}: nowhere for a robot of radius {config.robot_radius_m:g} m to stand")
        fits = np.argwhere(space.components == main)
        rng = np.random.default_rng(seed)
        start = fits[rng.integers(len(fits))]
        yaw = float(rng.uniform(-math.pi, math.pi))
        spec = GridSpec(space.origin, space.resolution, occupied.shape)
        labels, _ = ndimage.label(~occupied, structure=_EIGHT)
        free = labels == labels[start[0], start[1]]
        x, y = spec.to_world(start)
        return cls(spec, free, occupied, (float(x), float(y)), yaw)

    @property
    def area_m2(self) -> float:
        """The free floor to cover, in m²."""
        return float(self.free.sum()) * self.spec.resolution**2

    def clearance_m(self) -> np.ndarray:
        """What `agent.lfe.motion.take_action` checks a forward move against.

        Returns:
            Metres from each cell's centre to the nearest occupied cell's (outside the grid counts
            as occupied).
        """
        return clearance_to_obstacles(self.occupied, self.spec.resolution)[0]


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class Situation:
    """What a frontier chooser sees at a planning step: the partial map only.

    Args:
        spec: the grid.
        free: known free cells.
        occupied: known occupied cells.
        observed: ``free | occupied``.
        traversable: known free cells where the robot fits (for `agent.lfe.bellman.distance_matrix`).
        robot_xy: where the robot is (m).
        robot_cell: the cell it is in.
        frontiers: the reachable frontiers, never empty.
        from_robot_m: the known-space path length from the robot's cell to each frontier's centre.
        steps_left: primitive actions left in the budget.
    """

    spec: GridSpec
    free: np.ndarray
    occupied: np.ndarray
    observed: np.ndarray
    traversable: np.ndarray
    robot_xy: tuple[float, float]
    robot_cell: tuple[int, int]
    frontiers: list[Frontier]
    from_robot_m: np.ndarray
    steps_left: int


FrontierChooser = Callable[[Situation], int]
"""Returns an index into ``situation.frontiers``."""


@dataclass(frozen=True, eq=False)  # arrays: compared by identity
class CoverageResult:
    """How one exploration went.

    Args:
        coverage: (budget_steps + 1,) share of `TrueHome.free` observed after each step (index 0:
            before the first), padded with the last value if exploration ends early.
        steps_used: primitive actions taken.
        exhausted: no reachable frontier was left before the budget ran out.
        plan_seconds: time the chooser took at each planning step.
        frontier_counts: frontiers offered at each planning step.
        poses: (steps_used + 1, 3) x, y, yaw after each step (row 0: the start).
        blocked_steps: steps (1-based) whose forward move an obstacle stopped.
    """

    coverage: np.ndarray
    steps_used: int
    exhausted: bool
    plan_seconds: list[float]
    frontier_counts: list[int]
    poses: np.ndarray
    blocked_steps: list[int] = field(default_factory=list)


def clearance_to_obstacles(occupied: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """How far each cell is from the nearest obstacle, and which obstacle that is.

    Args:
        occupied: bool mask of the occupied cells; outside the grid counts as occupied.
        resolution: the cells' size (m).

    Returns:
        Metres from each cell's centre to the nearest occupied cell's, and that cell as a (2, H, W)
        array of (row, col) (cells outside the grid read -1 or the grid's size).
    """
    padded = np.pad(occupied, 1, constant_values=True)
    distances, nearest = ndimage.distance_transform_edt(~padded, return_indices=True)
    return distances[1:-1, 1:-1] * resolution, nearest[:, 1:-1, 1:-1] - 1
