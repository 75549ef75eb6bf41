"""The learned estimator: one estimate per frontier, the same whatever the map's cells or extent."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from agent.lfe.estimator import LearnedEstimator
from agent.lfe.model import FrontierUNet, UNetConfig, save_model
from agent.lfe.properties import FrontierProperties
from agent.mapping.grid import GridSpec
from agent.planning.frontier import Frontier, cluster_frontiers, frontier_cells

CONFIG = UNetConfig(base_channels=4, depth=3)


pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def estimator(tmp_path_factory: pytest.TempPathFactory) -> LearnedEstimator:
    """An untrained but fixed network: estimates are arbitrary yet exactly repeatable."""
    torch.manual_seed(0)
    model = FrontierUNet(CONFIG)
    with torch.no_grad():
        model.head.bias.fill_(1.0)  # outputs mostly above zero, so the clip does not hide everything
    path = tmp_path_factory.mktemp("model") / "unet.pt"
    save_model(path, model, CONFIG, {})
    return LearnedEstimator.load(path)


def partial_map() -> tuple[np.ndarray, np.ndarray, list[Frontier]]:
    """(known free, known occupied, frontiers) at 0.1 m: a room seen, with open doorways on two sides."""
    free = np.zeros((60, 80), dtype=bool)
    occupied = np.zeros_like(free)
    occupied[10:40, 10:40] = True
    free[11:39, 11:39] = True
    occupied[11:39, 11:39] = False
    free[20:25, 39] = free[39, 15:22] = True  # two doorways, into unknown space
    occupied[20:25, 39] = occupied[39, 15:22] = False
    explored = free | occupied
    mask = frontier_cells(free, explored, occupied, min_unexplored_neighbours=1)
    frontiers = cluster_frontiers(GridSpec((0.0, 0.0), 0.1, free.shape), mask, explored, occupied, min_size=1)
    return free, occupied, frontiers


def values(estimates: list[FrontierProperties]) -> list[tuple[float, float, float]]:
    return [(e.area_m2, e.d_in_m, e.d_out_m) for e in estimates]


def test_one_non_negative_estimate_per_frontier(estimator: LearnedEstimator) -> None:
    free, occupied, frontiers = partial_map()
    assert len(frontiers) == 2
    estimates = estimator.estimate(free, occupied, 0.1, frontiers)
    assert len(estimates) == 2 and all(isinstance(e, FrontierProperties) for e in estimates)
    assert all(np.isfinite(v) and v >= 0 for e in values(estimates) for v in e)
    assert any(v > 0 for e in values(estimates) for v in e)
    assert estimator.estimate(free, occupied, 0.1, []) == []


def test_frontier_cells_work_as_well_as_frontier_objects(estimator: LearnedEstimator) -> None:
    free, occupied, frontiers = partial_map()
    assert estimator.estimate(free, occupied, 0.1, [f.cells for f in frontiers]) == \
        estimator.estimate(free, occupied, 0.1, frontiers)


def test_a_map_at_five_centimetres_gives_the_same_estimates(estimator: LearnedEstimator) -> None:
    free, occupied, frontiers = partial_map()
    fine = np.ones((2, 2), dtype=bool)
    fine_frontiers = [np.concatenate([2 * f.cells, 2 * f.cells + 1]) for f in frontiers]
    assert estimator.estimate(np.kron(free, fine), np.kron(occupied, fine), 0.05, fine_frontiers) == \
        estimator.estimate(free, occupied, 0.1, frontiers)


def test_unknown_space_around_the_map_changes_nothing(estimator: LearnedEstimator) -> None:
    """Only the known cells and a margin are read: a 48 m grid gives what a tight one gives."""
    free, occupied, frontiers = partial_map()
    offset = np.array([170, 205])
    big_free, big_occupied = np.zeros((480, 480), dtype=bool), np.zeros((480, 480), dtype=bool)
    big_free[offset[0]:offset[0] + 60, offset[1]:offset[1] + 80] = free
    big_occupied[offset[0]:offset[0] + 60, offset[1]:offset[1] + 80] = occupied
    moved = [f.cells + offset for f in frontiers]
    assert estimator.estimate(big_free, big_occupied, 0.1, moved) == estimator.estimate(free, occupied, 0.1, frontiers)


def test_only_pixels_that_read_as_frontier_count(estimator: LearnedEstimator) -> None:
    """As in the training data: a frontier cell in a coarse wall cell changes nothing, yet a
    frontier with no frontier pixel at all still gets an estimate."""
    free, occupied, frontiers = partial_map()
    fine = np.ones((2, 2), dtype=bool)
    fine_frontiers = [2 * f.cells for f in frontiers]
    with_wall = [fine_frontiers[0], np.concatenate([fine_frontiers[1], [[2 * 10 + 1, 2 * 20]]])]
    assert occupied[10, 20]
    fine_free, fine_occupied = np.kron(free, fine), np.kron(occupied, fine)
    assert estimator.estimate(fine_free, fine_occupied, 0.05, with_wall) == \
        estimator.estimate(fine_free, fine_occupied, 0.05, fine_frontiers)
    inside = np.array([[50, 50], [50, 52]])  # known free, far from the unknown
    assert len(estimator.estimate(fine_free, fine_occupied, 0.05, [*fine_frontiers, inside])) == 3


def test_bad_frontiers_and_resolutions_are_refused(estimator: LearnedEstimator) -> None:
    free, occupied, frontiers = partial_map()
    with pytest.raises(ValueError, match="outside the grid"):
        estimator.estimate(free, occupied, 0.1, [np.array([[100, 0]])])
    with pytest.raises(ValueError, match="do not tile"):
        estimator.estimate(free, occupied, 0.03, frontiers)


def test_a_missing_model_says_how_to_train_one(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match=r"absent.pt.*homebot lfe train"):
        LearnedEstimator.load(tmp_path / "absent.pt")
