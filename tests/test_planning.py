"""Grids, shortest paths, frontiers and the exploration step, on maps drawn by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from agent.mapping.grid import GridSpec
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.planning.frontier_plan import ExploreConfig, plan_move, reachable_frontiers
from agent.planning.frontier_choice import FrontierChoiceConfig, choose_frontier
from agent.planning.frontier import cluster_frontiers, frontier_cells
from agent.planning.paths import distance_field, path_length, simplify_path, truncate_path

SQRT2 = math.sqrt(2.0)


# --- GridSpec ----------------------------------------------------------------------------------


def test_to_cell_to_world_round_trip() -> None:
    """Cell centres map back to their cells; points map to the cell that contains them."""
    spec = GridSpec((-2.0, 1.0), 0.1, (40, 60))
    rows, cols = np.indices(spec.shape)
    cells = np.stack([rows, cols], axis=-1)
    np.testing.assert_array_equal(spec.to_cell(spec.to_world(cells)), cells)
    # [row, col] = [iy, ix]: a point 0.35 m right and 0.12 m up from the origin
    np.testing.assert_array_equal(spec.to_cell(np.array([-2.0 + 0.35, 1.0 + 0.12])), [1, 3])
    np.testing.assert_allclose(spec.to_world(np.array([1, 3])), [-2.0 + 0.35, 1.0 + 0.15])
    # points outside map to cells outside
    outside = spec.to_cell(np.array([[-2.05, 1.0], [0.0, 5.05]]))
    assert not spec.inside(outside).any()
    assert spec.inside(np.array([[0, 0], [39, 59]])).all()
    assert not spec.inside(np.array([[40, 0], [0, 60], [-1, 0]])).any()


def test_centred_grid_and_disc() -> None:
    spec = GridSpec.centred((1.0, -1.0), 4.0, 0.1)
    assert spec.shape == (40, 40)
    np.testing.assert_allclose(spec.extent(), (-1.0, 3.0, -3.0, 1.0))
    centre_cell = tuple(spec.to_cell(np.array([1.0, -1.0])))
    assert centre_cell == (20, 20)
    disc = spec.disc((1.0, -1.0), 0.5)
    assert disc[centre_cell] and not disc[0, 0]
    # about pi r^2 of area
    assert disc.sum() * 0.01 == pytest.approx(math.pi * 0.25, rel=0.1)


# --- distance fields and paths -----------------------------------------------------------------


@pytest.fixture
def spec() -> GridSpec:
    return GridSpec((0.0, 0.0), 0.1, (20, 30))


def wall_grid(spec: GridSpec, gap_rows: tuple[int, ...] = (15,)) -> np.ndarray:
    """All traversable except column 10, which is a wall with gaps at ``gap_rows``."""
    traversable = np.ones(spec.shape, dtype=bool)
    traversable[:, 10] = False
    for row in gap_rows:
        traversable[row, 10] = True
    return traversable


def assert_chain(cells: np.ndarray, start: tuple[int, int], goal: tuple[int, int], traversable: np.ndarray) -> None:
    """``cells`` runs from start to goal in 8-neighbour steps over traversable cells."""
    assert tuple(cells[0]) == start and tuple(cells[-1]) == goal
    steps = np.abs(np.diff(cells, axis=0))
    assert (steps.max(axis=1) == 1).all(), "each step moves to an 8-neighbour"
    assert traversable[cells[1:, 0], cells[1:, 1]].all()


def test_straight_distance(spec: GridSpec) -> None:
    field = distance_field(spec, np.ones(spec.shape, dtype=bool), (5, 2))
    assert field.metres[5, 2] == 0.0
    assert field.metres[5, 12] == pytest.approx(1.0)  # 10 cells at 0.1 m
    assert field.metres[15, 12] == pytest.approx(SQRT2)  # 10 diagonal steps
    assert field.metres[8, 12] == pytest.approx((3 * SQRT2 + 7) * 0.1)  # octile


def test_distance_around_a_wall_through_its_gap(spec: GridSpec) -> None:
    traversable = wall_grid(spec)
    field = distance_field(spec, traversable, (5, 5))
    # to the gap (15, 10): 5 diagonal + 5 straight, then the same again to (5, 15)
    expected = 2 * (5 * SQRT2 + 5) * 0.1
    assert field.metres[5, 15] == pytest.approx(expected)
    assert field.metres[5, 15] > 1.0  # longer than the straight 10 cells through the wall
    assert np.isinf(field.metres[0, 10])  # wall cells are unreachable
    cells = field.path_to((5, 15))
    assert_chain(cells, (5, 5), (5, 15), traversable)
    assert (15, 10) in {tuple(c) for c in cells}
    assert path_length(spec.to_world(cells)) == pytest.approx(expected)


def test_closed_wall_makes_the_far_side_unreachable(spec: GridSpec) -> None:
    field = distance_field(spec, wall_grid(spec, gap_rows=()), (5, 5))
    assert np.isinf(field.metres[:, 11:]).all()
    assert np.isfinite(field.metres[:, :10]).all()
    with pytest.raises(ValueError, match=r"not reachable"):
        field.path_to((5, 15))


def test_start_on_a_blocked_cell_still_leaves(spec: GridSpec) -> None:
    """The robot stands where it stands: a start cell the map calls blocked still has distance 0."""
    traversable = np.ones(spec.shape, dtype=bool)
    traversable[5, 5] = False
    field = distance_field(spec, traversable, (5, 5))
    assert field.metres[5, 5] == 0.0
    assert field.metres[5, 8] == pytest.approx(0.3)


def test_path_to_is_a_connected_chain(spec: GridSpec) -> None:
    rng = np.random.default_rng(3)
    traversable = rng.random(spec.shape) > 0.25
    traversable[2, 2] = True
    field = distance_field(spec, traversable, (2, 2))
    reachable = np.argwhere(np.isfinite(field.metres))
    assert len(reachable) > 100
    for goal in reachable[rng.choice(len(reachable), 20, replace=False)]:
        goal_cell = (int(goal[0]), int(goal[1]))
        cells = field.path_to(goal_cell)
        if goal_cell == (2, 2):
            continue
        assert_chain(cells, (2, 2), goal_cell, traversable)
        assert path_length(spec.to_world(cells)) == pytest.approx(field.metres[goal_cell])


def test_truncate_path_cuts_at_exactly_the_length() -> None:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    cut = truncate_path(path, 2.0)
    np.testing.assert_allclose(cut, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert path_length(cut) == pytest.approx(2.0)
    cut = truncate_path(path, 0.25)
    np.testing.assert_allclose(cut, [[0.0, 0.0], [0.25, 0.0]])
    for limit in np.linspace(0.1, 2.9, 15):
        cut = truncate_path(path, limit)
        assert path_length(cut) == pytest.approx(limit)
        np.testing.assert_array_equal(cut[0], path[0])


def test_truncate_path_leaves_shorter_ones_alone() -> None:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    assert truncate_path(path, 3.0) is path
    assert truncate_path(path, 10.0) is path
    single = np.array([[1.0, 1.0]])
    assert truncate_path(single, 0.5) is single


def test_truncate_path_at_a_waypoint_has_no_zero_length_segment() -> None:
    """A cut that falls on a waypoint ends there, so the last segment still gives a heading."""
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    cut = truncate_path(path, 1.0)
    np.testing.assert_allclose(cut, [[0.0, 0.0], [1.0, 0.0]])
    assert np.hypot(*(cut[-1] - cut[-2])) > 0


def test_simplify_path_keeps_corners_and_drops_collinear_points() -> None:
    xs = np.arange(11) * 0.1
    leg1 = np.stack([xs, np.zeros(11)], axis=1)
    leg2 = np.stack([np.full(10, 1.0), xs[1:]], axis=1)
    path = np.vstack([leg1, leg2])
    np.testing.assert_allclose(simplify_path(path), [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    short = path[:2]
    assert simplify_path(short) is short


def test_simplify_path_keeps_a_bend_made_of_45_degree_steps() -> None:
    """A grid path that turns through a diagonal step keeps its bend and never strays from the cells."""
    cells = [(50, c) for c in range(30, 61)] + [(51, 61), (52, 62), (53, 63)] + [(r, 63) for r in range(54, 80)]
    spec = GridSpec((-5.0, -5.0), 0.1, (100, 100))
    path = spec.to_world(np.array(cells))
    simple = simplify_path(path)
    assert 3 <= len(simple) < len(path) // 4
    np.testing.assert_array_equal(simple[0], path[0])
    np.testing.assert_array_equal(simple[-1], path[-1])
    # every original point lies within the tolerance of the simplified polyline
    assert max(_distance_to_polyline(p, simple) for p in path) <= 0.05 + 1e-9


def _distance_to_polyline(point: np.ndarray, polyline: np.ndarray) -> float:
    best = math.inf
    for a, b in zip(polyline[:-1], polyline[1:]):
        d = b - a
        t = 0.0 if not d.any() else float(np.clip((point - a) @ d / (d @ d), 0, 1))
        best = min(best, float(np.hypot(*(point - a - t * d))))
    return best


# --- frontiers ---------------------------------------------------------------------------------


def test_one_frontier_along_the_boundary(spec: GridSpec) -> None:
    """Explored left half, unexplored right half: one cluster on the boundary column, normal +x."""
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:, :15] = True
    occupied = np.zeros(spec.shape, dtype=bool)
    mask = frontier_cells(explored, explored, occupied)
    assert mask[:, 14].all() and mask.sum() == spec.shape[0]
    frontiers = cluster_frontiers(spec, mask, explored, occupied)
    assert len(frontiers) == 1
    frontier = frontiers[0]
    assert frontier.size == spec.shape[0]
    assert frontier.centre[1] == 14 and 8 <= frontier.centre[0] <= 11
    np.testing.assert_allclose(frontier.normal, [1.0, 0.0], atol=1e-9)


def test_frontier_normal_points_up_into_unexplored_rows(spec: GridSpec) -> None:
    """Rows grow along +y: unexplored rows above the explored ones give a normal of (0, +1)."""
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:10, :] = True
    occupied = np.zeros(spec.shape, dtype=bool)
    frontiers = cluster_frontiers(spec, frontier_cells(explored, explored, occupied), explored, occupied)
    assert len(frontiers) == 1
    np.testing.assert_allclose(frontiers[0].normal, [0.0, 1.0], atol=1e-9)


def test_two_separated_boundaries_give_two_clusters(spec: GridSpec) -> None:
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:, 10:20] = True
    occupied = np.zeros(spec.shape, dtype=bool)
    frontiers = cluster_frontiers(spec, frontier_cells(explored, explored, occupied), explored, occupied)
    assert len(frontiers) == 2
    by_column = sorted(frontiers, key=lambda f: f.centre[1])
    assert set(by_column[0].cells[:, 1]) == {10} and set(by_column[1].cells[:, 1]) == {19}
    np.testing.assert_allclose(by_column[0].normal, [-1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(by_column[1].normal, [1.0, 0.0], atol=1e-9)


def test_walls_are_not_frontiers_and_small_clusters_are_dropped(spec: GridSpec) -> None:
    """Occupied cells do not count as unexplored; clusters below min_size are left out."""
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:, :15] = True
    occupied = np.zeros(spec.shape, dtype=bool)
    occupied[:, 15] = True  # a wall along the whole boundary
    assert not frontier_cells(explored, explored, occupied).any()
    occupied[9:11, 15] = False  # a two-cell doorway
    mask = frontier_cells(explored, explored, occupied, min_unexplored_neighbours=1)
    assert 0 < mask.sum() <= 4
    assert cluster_frontiers(spec, mask, explored, occupied, min_size=5) == []
    assert len(cluster_frontiers(spec, mask, explored, occupied, min_size=1)) == 1


def test_frontier_cells_must_be_reachable(spec: GridSpec) -> None:
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:, :15] = True
    reachable = np.zeros(spec.shape, dtype=bool)
    reachable[:10, :15] = True
    mask = frontier_cells(reachable, explored, np.zeros(spec.shape, dtype=bool))
    assert mask[:10, 14].all() and not mask[10:].any()


# --- the exploration step ----------------------------------------------------------------------


ROBOT_XY = (-2.0, 0.0)


def corridor_map() -> ExplorationMap:
    """An L-shaped explored corridor with walls, open at its left end and at the top of its leg.

    Horizontal part: rows 42..57 (y -0.8..0.8), cols 10..90 (x -4.0..4.1); vertical leg: cols
    75..90 (x 2.5..4.1), up to row 90 (y 4.1). From ``ROBOT_XY`` the open left end is 2 m away and
    the corner more than 4 m, so one 3 m step toward the leg still runs along the corridor.
    """
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=10))
    explored = np.zeros(world_map.spec.shape, dtype=bool)
    explored[42:58, 10:91] = True
    explored[42:91, 75:91] = True
    occupied = np.zeros_like(explored)
    occupied[41, 9:92] = True
    occupied[58, 9:75] = True
    occupied[41:92, 91] = True
    occupied[58:92, 74] = True
    world_map.explored = explored
    world_map.floor_seen = explored.copy()
    world_map.occupied = occupied
    world_map.stood = np.zeros_like(explored)
    return world_map


def nearest_frontier(candidates) -> int | None:
    """FBE's choice with no earlier goal."""
    centres = np.array([list(f.centre) for f in candidates.frontiers], dtype=float).reshape(-1, 2)
    return choose_frontier(centres, candidates.distances_m, None, None, FrontierChoiceConfig(),
                           np.random.default_rng(0))


def test_reachable_frontiers_and_nearest() -> None:
    world_map = corridor_map()
    assert world_map.spec.shape == (100, 100)
    candidates = reachable_frontiers(world_map, ROBOT_XY)
    assert len(candidates.frontiers) == 2
    normals = sorted(tuple(np.round(f.normal, 6)) for f in candidates.frontiers)
    assert normals == [(-1.0, 0.0), (0.0, 1.0)]
    index = nearest_frontier(candidates)
    assert index is not None
    np.testing.assert_allclose(candidates.frontiers[index].normal, [-1.0, 0.0])  # the open left end
    assert candidates.distances_m[index] == candidates.distances_m.min()
    assert 1.9 <= candidates.distances_m[index] < 3.0  # about 2 m along the corridor
    assert candidates.distances_m.max() > 7.0  # round the corner and up the leg


def test_plan_move_to_the_nearer_frontier_is_not_truncated() -> None:
    world_map = corridor_map()
    candidates = reachable_frontiers(world_map, ROBOT_XY)
    plan = plan_move(candidates, nearest_frontier(candidates), ROBOT_XY)
    np.testing.assert_allclose(plan.path_xy[0], ROBOT_XY)
    np.testing.assert_allclose(plan.path_xy[-1], world_map.spec.to_world(np.array(plan.frontier.centre)))
    assert path_length(plan.path_xy) <= 3.0 + 1e-9
    assert plan.yaw == pytest.approx(math.pi)  # along the frontier normal, into the unknown
    assert plan.goal_distance_m == pytest.approx(float(candidates.distances_m.min()))


def test_plan_move_to_the_far_frontier_is_one_step_facing_along_its_normal() -> None:
    """The far frontier (around the corner) is cut to 3 m; the robot ends facing the frontier's normal."""
    world_map = corridor_map()
    candidates = reachable_frontiers(world_map, ROBOT_XY)
    far = int(np.argmax(candidates.distances_m))
    plan = plan_move(candidates, far, ROBOT_XY)
    np.testing.assert_allclose(plan.path_xy[0], ROBOT_XY)
    assert path_length(plan.path_xy) == pytest.approx(3.0)
    normal = candidates.frontiers[far].normal
    assert plan.yaw == pytest.approx(math.atan2(normal[1], normal[0]))
    assert_stays_in_free_space(world_map, np.isfinite(candidates.field.metres), plan.path_xy)


def test_whole_path_to_the_far_frontier_stays_in_free_space() -> None:
    """With a long step the plan turns the corner instead of cutting across the wall."""
    world_map = corridor_map()
    candidates = reachable_frontiers(world_map, ROBOT_XY)
    far = int(np.argmax(candidates.distances_m))
    plan = plan_move(candidates, far, ROBOT_XY, ExploreConfig(max_step_m=50.0))
    assert len(plan.path_xy) >= 3
    assert plan.yaw == pytest.approx(math.pi / 2)  # arrived: face along the normal (+y)
    assert_stays_in_free_space(world_map, np.isfinite(candidates.field.metres), plan.path_xy)


def assert_stays_in_free_space(world_map: ExplorationMap, reachable: np.ndarray, path_xy: np.ndarray) -> None:
    """Every point along the polyline is explored, not a wall, and within one cell of reachable space."""
    near_traversable = ndimage.binary_dilation(reachable, structure=np.ones((3, 3), dtype=bool))
    for a, b in zip(path_xy[:-1], path_xy[1:]):
        for t in np.linspace(0.0, 1.0, 200):
            cell = tuple(int(v) for v in world_map.spec.to_cell(a + t * (b - a)))
            assert world_map.explored[cell] and not world_map.occupied[cell], f"the path crosses {cell}"
            assert near_traversable[cell], f"the path leaves the free space at {cell}"


def test_near_frontiers_are_dropped_and_none_left_gives_none() -> None:
    world_map = corridor_map()
    # standing 0.5 m from the left end: with a 1 m minimum that frontier is where the robot already is
    candidates = reachable_frontiers(world_map, (-3.5, 0.0), ExploreConfig(min_frontier_distance_m=1.0))
    assert len(candidates.frontiers) == 1
    np.testing.assert_allclose(candidates.frontiers[0].normal, [0.0, 1.0])
    assert (candidates.distances_m >= 1.0).all()
    candidates = reachable_frontiers(world_map, (-3.5, 0.0), ExploreConfig(min_frontier_distance_m=0.2))
    assert len(candidates.frontiers) == 2
    # close both open ends: nothing left to explore
    world_map.occupied[42:58, 9] = True
    world_map.occupied[91, 75:91] = True
    candidates = reachable_frontiers(world_map, ROBOT_XY)
    assert candidates.frontiers == [] and len(candidates.distances_m) == 0
    assert nearest_frontier(candidates) is None
