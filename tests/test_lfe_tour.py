"""The closed tour through a region's key nodes: exact against brute force, close beyond the exact limit."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from agent.lfe.tour import EXACT_TOUR_NODES, _held_karp, tour_split


def brute_force_split(distances: np.ndarray) -> tuple[float, float]:
    """Every order of the nodes after 0: shortest tour, then the smallest D_in among those."""
    best: tuple[float, float, float] | None = None
    for order in itertools.permutations(range(1, len(distances))):
        path = (0, *order)
        d_in = sum(distances[a, b] for a, b in itertools.pairwise(path))
        d_out = distances[order[-1], 0]
        total = d_in + d_out
        if best is None or total < best[0] - 1e-9 or (abs(total - best[0]) <= 1e-9 and d_in < best[1]):
            best = (total, d_in, d_out)
    assert best is not None
    return best[1], best[2]


@pytest.mark.parametrize("seed", range(40))
def test_tour_split_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 8))
    if seed % 2:  # Euclidean, symmetric
        points = rng.random((n, 2))
        distances = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
    else:  # small integers: many equal tours, and asymmetric
        distances = rng.integers(1, 5, (n, n)).astype(float)
        np.fill_diagonal(distances, 0.0)
    assert tour_split(distances) == pytest.approx(brute_force_split(distances))


def test_tour_of_one_node_is_empty() -> None:
    assert tour_split(np.zeros((1, 1))) == (0.0, 0.0)


@pytest.mark.parametrize("seed", range(10))
def test_approximate_tour_is_close_to_exact(seed: int) -> None:
    """Beyond the exact limit the greedy tour and 2-opt take over: within 8 % of Held–Karp here."""
    rng = np.random.default_rng(seed)
    points = rng.random((EXACT_TOUR_NODES + 1, 2))
    distances = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
    exact = (_held_karp(distances) + distances[1:, 0]).min()
    d_in, d_out = tour_split(distances)
    assert exact - 1e-9 <= d_in + d_out <= 1.08 * exact


def test_bad_distances_are_refused() -> None:
    with pytest.raises(ValueError, match="distances"):
        tour_split(np.zeros((2, 3)))
