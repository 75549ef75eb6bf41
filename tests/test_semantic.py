"""Prompt points, the semantic map and semantic-value-weighted frontier choice, on hand-made arrays."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest
from scipy import stats

from agent.mapping.camera import Intrinsics
from agent.mapping.grid import GridSpec
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.mapping.semantic_map import SemanticMap, SemanticValueConfig, indifferent_value, semantic_value
from agent.planning.frontier_plan import reachable_frontiers
from agent.planning.frontier import cluster_frontiers, frontier_cells
from agent.planning.prompt_points import (
    PromptPointConfig,
    farthest_point_sample,
    prompt_points,
    visible_free_cells,
)
from agent.planning.frontier_choice import FrontierChoiceConfig, choose_frontier, frontier_probabilities, sample_frontier
from agent.planning.explore_method import ExploreMethod, ExploreStrategy
from agent.planning.semantic import FrontierWeightConfig, frontier_log_weights, normal_ray_cells

# --- a camera over an open floor ----------------------------------------------------------------

INTRINSICS = Intrinsics(160, 120, 80.0, 80.0, 80.0, 60.0)  # 90° HFOV
CAMERA_HEIGHT = 1.5
PITCH = 0.2  # radians down from level


def camera_pose(xy: tuple[float, float] = (0.0, 0.0), yaw: float = 0.0, pitch: float = PITCH) -> np.ndarray:
    """OpenCV camera (x right, y down, z ahead) at ``CAMERA_HEIGHT`` looking along ``yaw``, tilted down."""
    forward = np.array([math.cos(yaw) * math.cos(pitch), math.sin(yaw) * math.cos(pitch), -math.sin(pitch)])
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.cross(forward, right)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([right, down, forward])
    pose[:3, 3] = [xy[0], xy[1], CAMERA_HEIGHT]
    return pose


def render_depth(pose: np.ndarray, boxes: tuple[tuple[np.ndarray, np.ndarray], ...] = (),
                 max_range: float = 15.0) -> np.ndarray:
    """Linear depth of the floor z = 0 and axis-aligned boxes (low corner, high corner); 0 = no return."""
    rows, cols = np.indices((INTRINSICS.height, INTRINSICS.width))
    rays = np.stack([(cols + 0.5 - INTRINSICS.cx) / INTRINSICS.fx, (rows + 0.5 - INTRINSICS.cy) / INTRINSICS.fy,
                     np.ones(rows.shape)], axis=-1) @ pose[:3, :3].T  # camera z = 1 per unit of s
    origin = pose[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(rays[..., 2] < 0, -origin[2] / rays[..., 2], np.inf)
        for low, high in boxes:
            t0, t1 = (low - origin) / rays, (high - origin) / rays
            near = np.minimum(t0, t1).max(axis=-1)
            far = np.maximum(t0, t1).min(axis=-1)
            depth = np.where((near <= far) & (near > 0), np.minimum(depth, near), depth)
    return np.where(depth <= max_range, depth, 0.0).astype(np.float32)


def floor_map(free: np.ndarray | None = None, size_m: float = 24.0) -> ExplorationMap:
    """A map centred on the origin whose free cells are ``free`` (everything when None)."""
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=size_m))
    shape = world_map.spec.shape
    world_map.floor_seen = np.ones(shape, dtype=bool) if free is None else free
    world_map.occupied = np.zeros(shape, dtype=bool)
    world_map.explored = np.zeros(shape, dtype=bool)
    world_map.stood = np.zeros(shape, dtype=bool)
    return world_map


def cell_centres(world_map: ExplorationMap) -> np.ndarray:
    rows, cols = np.indices(world_map.spec.shape)
    return world_map.spec.to_world(np.stack([rows, cols], axis=-1))


def project(pose: np.ndarray, xy: np.ndarray) -> np.ndarray:
    point = np.linalg.inv(pose) @ np.array([xy[0], xy[1], 0.0, 1.0])
    return np.array([INTRINSICS.fx * point[0] / point[2] + INTRINSICS.cx,
                     INTRINSICS.fy * point[1] / point[2] + INTRINSICS.cy])


# --- prompt points ------------------------------------------------------------------------------


def test_prompt_points_are_free_in_view_in_range_and_apart() -> None:
    world_map = floor_map()
    pose = camera_pose()
    points = prompt_points(world_map, (0.0, 0.0), render_depth(pose), INTRINSICS, pose, np.random.default_rng(0))
    assert 2 <= len(points) <= 3
    assert [p.letter for p in points] == list("ABC")[: len(points)]
    for point in points:
        cell = tuple(world_map.spec.to_cell(np.array(point.xy)))
        assert world_map.free[cell]
        assert 2.0 <= math.hypot(*point.xy) <= 10.0
        u, v = point.pixel
        assert 0 <= u < INTRINSICS.width and 0 <= v < INTRINSICS.height
        np.testing.assert_array_equal(np.floor(project(pose, np.array(point.xy))), [u, v])
    for a, b in combinations(points, 2):
        assert math.dist(a.xy, b.xy) >= 1.0


def test_candidates_keep_to_the_distance_band_and_the_view() -> None:
    world_map = floor_map()
    pose = camera_pose(yaw=0.5)
    depth = render_depth(pose)
    xy, pixels = visible_free_cells(world_map, (0.0, 0.0), depth, INTRINSICS, pose)
    distance = np.hypot(*xy.T)
    assert len(xy) > 100 and distance.min() >= 2.0 and distance.max() <= 10.0
    assert distance.max() > 9.0  # the band's far end is in view and used
    wider, _ = visible_free_cells(world_map, (0.0, 0.0), depth, INTRINSICS, pose,
                                  PromptPointConfig(max_distance_m=12.0))
    assert np.hypot(*wider.T).max() > 10.0  # so the 10 m cut is what removed them
    # around yaw 0.5 within the field of view (90° wide, a little more on the floor near the
    # lower image corners of the tilted camera), never behind the camera
    bearing = np.arctan2(xy[:, 1], xy[:, 0]) - 0.5
    assert np.abs(bearing).max() < 1.0
    for point in xy[::50]:
        assert (np.linalg.inv(pose) @ np.array([*point, 0.0, 1.0]))[2] > 0
    assert ((pixels >= 0) & (pixels < [INTRINSICS.width, INTRINSICS.height])).all()


def test_points_behind_a_wall_are_not_chosen() -> None:
    """A corridor along +x with a wall across it at x = 5: only the floor in front of the wall is in sight.

    The map still calls the cells behind the wall free (as if seen from elsewhere); the depth image
    shows the wall, so they must not be lettered.
    """
    world_map = floor_map()
    centres = cell_centres(world_map)
    world_map.floor_seen = (np.abs(centres[..., 1]) < 1.5) & (centres[..., 0] > 0)
    pose = camera_pose(pitch=0.1)
    open_depth = render_depth(pose)
    wall = (np.array([5.0, -1.0, 0.0]), np.array([5.2, 1.0, 2.0]))
    walled_depth = render_depth(pose, (wall,))

    xy, _ = visible_free_cells(world_map, (0.0, 0.0), open_depth, INTRINSICS, pose)
    assert xy[:, 0].max() > 9.0  # without the wall the far corridor is in sight
    xy, _ = visible_free_cells(world_map, (0.0, 0.0), walled_depth, INTRINSICS, pose)
    assert len(xy) > 0 and not in_shadow(xy).any()
    assert xy[:, 0].max() < 7.6  # past 7.5 m the shadow covers the whole corridor
    assert (xy[:, 0] > 5.2).any()  # floor seen past the wall's ends is still in sight
    for seed in range(10):
        points = prompt_points(world_map, (0.0, 0.0), walled_depth, INTRINSICS, pose, np.random.default_rng(seed))
        assert len(points) >= 2
        assert not in_shadow(np.array([p.xy for p in points])).any()


def in_shadow(xy: np.ndarray) -> np.ndarray:
    """Behind the wall x = 5..5.2, |y| ≤ 1 as seen from the origin (with a little margin at the ends)."""
    return (xy[:, 0] > 5.2) & (np.abs(xy[:, 1]) * 5.0 / xy[:, 0] < 0.95)


def test_floor_hidden_behind_a_low_obstacle_is_not_a_candidate() -> None:
    """A 0.3 m high bench across the view at x = 4..4.3 hides the floor out to 4.3 · 1.5 / 1.2 m."""
    world_map = floor_map()
    pose = camera_pose()
    bench = (np.array([4.0, -5.0, 0.0]), np.array([4.3, 5.0, 0.3]))
    xy, _ = visible_free_cells(world_map, (0.0, 0.0), render_depth(pose, (bench,)), INTRINSICS, pose)
    hidden_to = 4.3 * CAMERA_HEIGHT / (CAMERA_HEIGHT - 0.3)
    assert not ((xy[:, 0] > 4.3) & (xy[:, 0] < hidden_to - 0.1)).any()  # behind it, not under it
    assert (xy[:, 0] > hidden_to + 0.1).any() and (xy[:, 0] < 4.0).any()


def test_no_prompt_with_fewer_than_two_candidates() -> None:
    world_map = floor_map()
    centres = cell_centres(world_map)
    pose = camera_pose()
    depth = render_depth(pose)
    one_cell = np.zeros(world_map.spec.shape, dtype=bool)
    one_cell[tuple(world_map.spec.to_cell(np.array([5.05, 0.05])))] = True
    world_map.floor_seen = one_cell
    assert prompt_points(world_map, (0.0, 0.0), depth, INTRINSICS, pose, np.random.default_rng(0)) == []
    # a patch smaller than the merge distance: its candidates merge into one point
    world_map.floor_seen = np.hypot(centres[..., 0] - 5.0, centres[..., 1]) < 0.4
    assert len(visible_free_cells(world_map, (0.0, 0.0), depth, INTRINSICS, pose)[0]) > 5
    assert prompt_points(world_map, (0.0, 0.0), depth, INTRINSICS, pose, np.random.default_rng(0)) == []
    # nothing free at all
    world_map.floor_seen = np.zeros(world_map.spec.shape, dtype=bool)
    assert prompt_points(world_map, (0.0, 0.0), depth, INTRINSICS, pose, np.random.default_rng(0)) == []


def test_farthest_point_sampling_spreads_points_more_than_random_picks() -> None:
    world_map = floor_map()
    pose = camera_pose()
    xy, _ = visible_free_cells(world_map, (0.0, 0.0), render_depth(pose), INTRINSICS, pose)

    def min_gap(points: np.ndarray) -> float:
        return min(math.dist(a, b) for a, b in combinations(points, 2))

    fps_gaps, random_gaps = [], []
    for seed in range(30):
        rng = np.random.default_rng(seed)
        fps_gaps.append(min_gap(xy[farthest_point_sample(xy, 3, 1.0, rng)]))
        random_gaps.append(min_gap(xy[rng.choice(len(xy), 3, replace=False)]))
    assert min(fps_gaps) > np.median(random_gaps)
    assert np.mean(fps_gaps) > 1.5 * np.mean(random_gaps)


def test_farthest_point_sampling_on_a_line_and_its_merge_rule() -> None:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [4.0, 0.0], [4.5, 0.0]])
    rng = np.random.default_rng(3)
    chosen = farthest_point_sample(points, 3, 1.0, rng)
    assert len(set(chosen.tolist())) == len(chosen) == 3
    gaps = [abs(points[a, 0] - points[b, 0]) for a, b in combinations(chosen, 2)]
    assert min(gaps) >= 1.0
    # with a 2 m merge distance at most the two ends survive
    assert len(farthest_point_sample(points, 3, 2.0, np.random.default_rng(3))) == 2
    assert len(farthest_point_sample(np.zeros((0, 2)), 3, 1.0, rng)) == 0


def test_prompt_points_are_deterministic_for_a_seed() -> None:
    world_map = floor_map()
    pose = camera_pose()
    depth = render_depth(pose)

    def run(seed: int) -> list:
        return prompt_points(world_map, (0.0, 0.0), depth, INTRINSICS, pose, np.random.default_rng(seed))

    assert run(7) == run(7)
    assert len({tuple(p.xy for p in run(seed)) for seed in range(10)}) > 1  # the start is random


# --- semantic value and map ---------------------------------------------------------------------


def test_semantic_value_formula_and_indifferent_default() -> None:
    config = SemanticValueConfig(tau_lsv=3.0, tau_gsv=5.0)
    assert float(semantic_value(0.2, 0.7, config)) == pytest.approx(math.exp(3.0 * 0.2 + 5.0 * 0.7))
    np.testing.assert_allclose(semantic_value(np.array([0.0, 0.5, 1.0]), 0.0), np.exp([0.0, 0.5, 1.0]))
    assert indifferent_value() == pytest.approx(math.exp(1 / 3 + 1 / 2))
    assert indifferent_value(use_lsv=False) == pytest.approx(math.exp(0.5))
    assert indifferent_value(use_gsv=False) == pytest.approx(math.exp(1 / 3))
    low, high = float(semantic_value(0.0, 0.0)), float(semantic_value(1.0, 1.0))
    assert low < indifferent_value() < high


def test_map_update_is_a_gaussian_disc_around_the_point() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (60, 60))
    semantic_map = SemanticMap(spec, default=2.0)
    centre = spec.to_world(np.array([30, 30]))
    semantic_map.update(centre[None, :], np.array([5.0]))
    values = semantic_map.values()
    assert values[30, 30] == pytest.approx(5.0)
    along = values[30, 30:45]  # 0 .. 1.4 m to the right
    assert (np.diff(along[:11]) < 0).all()  # fades with distance inside the disc
    assert along[5] == pytest.approx(2.0 + math.exp(-0.5**2 / (2 * 0.5**2)) * 3.0)  # at 0.5 m
    assert (semantic_map.weight[30, 41:] == 0).all() and (along[11:] == 2.0).all()  # beyond 1 m
    assert semantic_map.weight[30, 40] > 0  # exactly 1 m is inside
    assert values[0, 0] == 2.0


def test_second_update_at_the_same_place_averages() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (60, 60))
    semantic_map = SemanticMap(spec, default=2.0)
    centre = spec.to_world(np.array([30, 30]))
    semantic_map.update(centre[None, :], [5.0])
    semantic_map.update(centre[None, :], [3.0])
    assert semantic_map.values()[30, 30] == pytest.approx(4.0)
    np.testing.assert_allclose(semantic_map.mean()[30, 25:36], 4.0)  # the running mean in the whole disc
    # two points of one image fold in the same way as two updates
    both = SemanticMap(spec, default=2.0)
    both.update(np.vstack([centre, centre]), [5.0, 3.0])
    np.testing.assert_allclose(both.values(), semantic_map.values())


def test_values_at_some_cells_are_the_whole_maps_to_the_bit() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (60, 80))
    semantic_map = SemanticMap(spec, default=1.7)
    rng = np.random.default_rng(5)
    semantic_map.update(rng.uniform(0.0, 6.0, (7, 2)), rng.uniform(0.5, 4.0, 7))
    cells = np.argwhere(np.ones(spec.shape, dtype=bool))[rng.permutation(60 * 80)[:500]]
    values = semantic_map.values()
    np.testing.assert_array_equal(semantic_map.values_at(cells), values[cells[:, 0], cells[:, 1]])
    assert semantic_map.values_at(np.array([12, 3]))[0] == values[12, 3]


def test_map_update_at_the_edge_and_outside_the_grid() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (20, 20))
    semantic_map = SemanticMap(spec, default=1.0)
    semantic_map.update([[0.05, 0.05]], [4.0])  # a corner: only a quarter disc is inside
    assert semantic_map.values()[0, 0] == pytest.approx(4.0)
    before = semantic_map.weight.copy()
    semantic_map.update([[-5.0, -5.0], [50.0, 1.0]], [9.0, 9.0])
    np.testing.assert_array_equal(semantic_map.weight, before)
    with pytest.raises(ValueError):
        semantic_map.update([[1.0, 1.0]], [1.0, 2.0])


# --- methods and their ablations ----------------------------------------------------------------


def test_explore_strategies() -> None:
    assert ExploreStrategy.of("fbe") == ExploreStrategy.of(ExploreMethod.FBE)
    flags = {m.value: ExploreStrategy.of(m) for m in ExploreMethod}
    assert [(f.use_lsv, f.use_gsv, f.use_semantic, f.learned) for f in flags.values()] == [
        (False, False, False, False), (True, True, True, False), (False, True, True, False),
        (True, False, True, False), (False, False, False, True)]
    assert list(flags) == ["fbe", "semantic", "semantic-no-lsv", "semantic-no-gsv", "lfe"]
    with pytest.raises(ValueError):
        ExploreStrategy.of("clip-fbe")


def test_point_values_apply_the_ablations() -> None:
    letters, p_yes = [0.6, 0.3, 0.1], 0.8
    np.testing.assert_allclose(ExploreStrategy.of("semantic").point_values(letters, p_yes), np.exp(np.array(letters) + 0.8))
    np.testing.assert_allclose(ExploreStrategy.of("semantic").point_values([6, 3, 1], p_yes), np.exp(np.array(letters) + 0.8))
    np.testing.assert_allclose(ExploreStrategy.of("semantic-no-lsv").point_values(letters, p_yes), np.full(3, math.exp(0.8)))
    np.testing.assert_allclose(ExploreStrategy.of("semantic-no-gsv").point_values(letters, p_yes), np.exp(letters))
    np.testing.assert_allclose(ExploreStrategy.of("semantic").point_values([0.0, 0.0], 0.5), np.full(2, math.exp(0.5 + 0.5)))
    no_lsv_map = ExploreStrategy.of("semantic-no-lsv").new_semantic_map(GridSpec((0.0, 0.0), 0.1, (5, 5)))
    assert no_lsv_map.default == pytest.approx(math.exp(0.5))


# --- frontier weights and sampling --------------------------------------------------------------


def band_frontiers() -> tuple[GridSpec, list]:
    """A 10 m × 4 m grid explored in the middle (x 4..6 m): frontiers facing -x (left) and +x (right)."""
    spec = GridSpec((0.0, 0.0), 0.1, (40, 100))
    explored = np.zeros(spec.shape, dtype=bool)
    explored[:, 40:60] = True
    occupied = np.zeros(spec.shape, dtype=bool)
    frontiers = cluster_frontiers(spec, frontier_cells(explored, explored, occupied), explored, occupied)
    return spec, sorted(frontiers, key=lambda f: f.centre[1])


def test_normal_ray_runs_along_the_normal_inside_the_grid() -> None:
    spec, (left, right) = band_frontiers()
    ray = normal_ray_cells(spec, right, 3.0)
    assert len(ray) == 30 and (ray[:, 0] == right.centre[0]).all()
    np.testing.assert_array_equal(ray[:, 1], right.centre[1] + np.arange(1, 31))
    assert len(normal_ray_cells(spec, left, 10.0)) == left.centre[1]  # stops at the grid's edge


def test_a_frontier_facing_a_valued_region_outweighs_one_facing_neutral_space() -> None:
    """App. B, Fig. A1: same SV at both frontiers, but one looks toward a high value 2 m beyond it."""
    spec, (left, right) = band_frontiers()
    semantic_map = SemanticMap(spec)
    target = spec.to_world(np.array(right.centre)) + [2.0, 0.0]
    semantic_map.update(target[None, :], [float(semantic_value(1.0, 1.0))])
    values = semantic_map.values()
    assert values[left.centre] == values[right.centre] == semantic_map.default
    logs = frontier_log_weights([left, right], semantic_map, FrontierWeightConfig())
    assert logs[1] > logs[0]
    assert logs[0] == pytest.approx(2 * semantic_map.default)  # neutral everywhere it looks


def test_log_weights_follow_eq_a6_on_a_constant_map() -> None:
    spec, frontiers = band_frontiers()
    constant = SemanticMap(spec, default=3.0)  # nothing written: the default everywhere
    logs = frontier_log_weights(frontiers, constant, FrontierWeightConfig(tau_sv=2.0, tau_sv_normal=0.5))
    np.testing.assert_allclose(logs, 2.0 * 3.0 + 0.5 * 3.0)


def test_sampling_is_proportional_to_the_weights() -> None:
    log_weights = np.log(np.array([1.0, 2.0, 3.0, 4.0])) + 700.0  # exp(700+) alone would overflow
    probabilities = frontier_probabilities(log_weights)
    np.testing.assert_allclose(probabilities, [0.1, 0.2, 0.3, 0.4])
    rng = np.random.default_rng(42)
    draws = np.array([sample_frontier(log_weights, rng) for _ in range(20_000)])
    counts = np.bincount(draws, minlength=4)
    assert stats.chisquare(counts, probabilities * len(draws)).pvalue > 0.001
    with pytest.raises(ValueError):
        sample_frontier(np.zeros(0), rng)


def test_huge_exponents_stay_finite_and_pick_the_largest() -> None:
    probabilities = frontier_probabilities(np.array([1e5, 1e5 - 50.0, -1e5]))
    assert np.isfinite(probabilities).all() and probabilities[0] > 0.999999


def test_sampling_is_deterministic_for_a_seed() -> None:
    logs = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    first = [sample_frontier(logs, np.random.default_rng(5)) for _ in range(3)]
    rng_a, rng_b = np.random.default_rng(11), np.random.default_rng(11)
    assert [sample_frontier(logs, rng_a) for _ in range(50)] == [sample_frontier(logs, rng_b) for _ in range(50)]
    assert len(set(first)) == 1


def test_sampled_choice_on_reachable_frontiers_follows_the_weights() -> None:
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=10))
    explored = np.zeros(world_map.spec.shape, dtype=bool)
    explored[:, 40:60] = True  # explored band x -1..1; open to both sides
    world_map.explored, world_map.floor_seen = explored, explored.copy()
    world_map.occupied = np.zeros_like(explored)
    world_map.stood = np.zeros_like(explored)
    candidates = reachable_frontiers(world_map, (0.0, 0.0))
    assert len(candidates.frontiers) == 2
    right = int(np.argmax([f.normal[0] for f in candidates.frontiers]))
    semantic_map = ExploreStrategy.of("semantic").new_semantic_map(world_map.spec)
    beyond = world_map.spec.to_world(np.array(candidates.frontiers[right].centre)) + [1.5, 0.0]
    semantic_map.update(beyond[None, :], [float(semantic_value(1.0, 1.0))])
    logs = frontier_log_weights(candidates.frontiers, semantic_map, FrontierWeightConfig())
    assert frontier_probabilities(logs)[right] > 0.6
    centres = world_map.spec.to_world(np.array([f.centre for f in candidates.frontiers]))
    rng = np.random.default_rng(0)
    paper = FrontierChoiceConfig(rule="sample")
    picks = [choose_frontier(centres, candidates.distances_m, logs, None, paper, rng) for _ in range(200)]
    assert sum(index == right for index in picks) > 100
    assert choose_frontier(np.zeros((0, 2)), np.zeros(0), np.zeros(0), None, paper, rng) is None


# --- frontier normals on hand-made maps ---------------------------------------------------------


def normals_of(explored: np.ndarray, occupied: np.ndarray | None = None) -> list[np.ndarray]:
    spec = GridSpec((0.0, 0.0), 0.1, explored.shape)
    occupied = np.zeros_like(explored) if occupied is None else occupied
    reachable = explored & ~occupied
    mask = frontier_cells(reachable, explored, occupied)
    return [f.normal for f in cluster_frontiers(spec, mask, explored, occupied)]


@pytest.mark.parametrize(("region", "normal"), [
    ((slice(None), slice(0, 15)), (1.0, 0.0)),  # explored left half: look right (+x)
    ((slice(None), slice(15, 30)), (-1.0, 0.0)),
    ((slice(0, 10), slice(None)), (0.0, 1.0)),  # explored low rows (low y): look up (+y)
    ((slice(10, 20), slice(None)), (0.0, -1.0)),
])
def test_half_plane_normals_point_into_the_unexplored_half(region: tuple[slice, slice], normal: tuple) -> None:
    explored = np.zeros((20, 30), dtype=bool)
    explored[region] = True
    (found,) = normals_of(explored)
    np.testing.assert_allclose(found, normal, atol=1e-9)


def test_corner_normal_points_diagonally_out_of_an_explored_quadrant() -> None:
    explored = np.zeros((30, 30), dtype=bool)
    explored[:15, :15] = True  # the lower-left quadrant
    (found,) = normals_of(explored)  # the L of boundary cells is one cluster
    assert found[0] > 0.5 and found[1] > 0.5
    assert found[0] == pytest.approx(found[1]) and np.hypot(*found) == pytest.approx(1.0)


def test_walls_do_not_pull_the_normal() -> None:
    """Explored lower-left quadrant, the area above it walled off: only the +x side is open."""
    explored = np.zeros((30, 30), dtype=bool)
    explored[:15, :15] = True
    occupied = np.zeros_like(explored)
    occupied[15, :16] = True
    (found,) = normals_of(explored, occupied)
    assert found[0] > 0.95 and abs(found[1]) < 0.3
