"""Discs marked into the floor grid: the union of many discs at once equals the discs one by one,
and the path the base drove marks exactly the cells within its radius of the samples along it."""

from __future__ import annotations

import numpy as np

from agent.mapping.grid import GridSpec
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig


def _one_by_one(spec: GridSpec, centres: np.ndarray, radius: float) -> np.ndarray:
    union = np.zeros(spec.shape, dtype=bool)
    for centre in centres:
        union |= spec.disc(tuple(centre), radius)
    return union


def test_the_union_of_discs_equals_the_discs_one_by_one_even_off_the_grid() -> None:
    spec = GridSpec.centred((0.3, -0.2), 6.0, 0.1)
    rng = np.random.default_rng(5)
    for _ in range(100):
        centres = rng.uniform(-4.5, 4.5, (rng.integers(1, 9), 2))
        radius = float(rng.uniform(0.05, 1.2))
        expected = _one_by_one(spec, centres, radius)
        window = spec.discs_window(centres, radius)
        marked = np.zeros(spec.shape, dtype=bool)
        if window is not None:
            marked[window[0]] = window[1]
        assert np.array_equal(marked, expected)
    assert spec.discs_window(np.array([[50.0, 50.0]]), 0.5) is None


def test_a_driven_path_marks_the_cells_near_its_samples() -> None:
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig())
    path = np.array([[0.0, 0.0], [1.0, 0.35], [1.0, 2.0]])
    world_map.mark_driven(path)
    step = world_map.spec.resolution / 2
    samples = [start + t * (end - start) for start, end in zip(path[:-1], path[1:])
               for t in np.linspace(0.0, 1.0, int(np.ceil(np.hypot(*(end - start)) / step)) + 1)]
    expected = _one_by_one(world_map.spec, np.array(samples), world_map.config.driven_radius)
    assert np.array_equal(world_map.driven, expected)
    assert expected.sum() > 50
