"""The network shipped with homebot: it loads, predicts usefully on homes it never saw, and drives
the EQA tree's `lfe` exploration method."""

from __future__ import annotations

import numpy as np
import py_trees
import pytest
from py_trees.common import Access, Status
from scipy.stats import spearmanr

from behaviours import blackboard as bb
from agent.planning.map_fields import MapFields
from agent.eqa.answers import AnswerLog
from agent.app.eval.coverage import SEED_BASE
from agent.lfe.coverage import fbe_near, run_coverage
from agent.lfe.estimator import SHIPPED_MODEL, LearnedEstimator
from agent.lfe.properties import label_frontiers
from agent.lfe.task import CoverageConfig, Situation, TrueHome
from agent.mapping.camera import Intrinsics
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.observation import Observation
from agent.planning.frontier_plan import ExploreConfig
from behaviours.select_frontier import SelectFrontier
from worlds.home import generate_home

pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def estimator() -> LearnedEstimator:
    return LearnedEstimator.load()


def test_the_shipped_model_is_small_and_says_how_it_was_trained(estimator: LearnedEstimator) -> None:
    assert SHIPPED_MODEL.stat().st_size < 4_000_000
    assert estimator.config.model_resolution == pytest.approx(0.1)


def test_predicted_area_ranks_frontiers_like_the_truth_on_unseen_homes(estimator: LearnedEstimator) -> None:
    """Over the frontiers met while exploring two evaluation homes (seeds never trained on), the
    predicted R_A and D_in rise with the true ones."""
    predicted: list[tuple[float, float]] = []
    truth: list[tuple[float, float]] = []

    def record(situation: Situation, _: int, home: TrueHome) -> None:
        for guess, true in zip(estimator.estimate(situation.free, situation.occupied, situation.spec.resolution,
                                                  situation.frontiers),
                               label_frontiers(home.free, situation.observed, situation.frontiers,
                                               situation.spec.resolution)):
            predicted.append((guess.area_m2, guess.d_in_m))
            truth.append((true.area_m2, true.d_in_m))

    config = CoverageConfig(budget_steps=120, replan_every=10)
    for seed, area in ((SEED_BASE + 7, 120.0), (SEED_BASE + 8, 220.0)):
        home = TrueHome.from_home(generate_home(seed, area_m2=area), config, seed)
        run_coverage(home, fbe_near, config, on_plan=lambda situation, index: record(situation, index, home))
    predicted_array, truth_array = np.array(predicted), np.array(truth)
    assert len(predicted) >= 20
    assert spearmanr(predicted_array[:, 0], truth_array[:, 0]).statistic > 0.3
    assert spearmanr(predicted_array[:, 1], truth_array[:, 1]).statistic > 0.3


def corridor_map() -> ExplorationMap:
    """An explored corridor, open at both ends: rows 45..54, cols 10..89 of a 10 m map at 0.1 m."""
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=10))
    explored = np.zeros(world_map.spec.shape, dtype=bool)
    explored[45:55, 10:90] = True
    occupied = np.zeros_like(explored)
    occupied[44, 9:91] = occupied[55, 9:91] = True
    world_map.explored, world_map.floor_seen, world_map.occupied = explored, explored.copy(), occupied
    world_map.stood = np.zeros_like(explored)
    return world_map


def test_the_tree_s_lfe_method_plans_a_move_toward_a_frontier() -> None:
    board = py_trees.blackboard.Client(name="test")
    for key in (bb.MAP, bb.OBSERVATION, bb.BUDGET, bb.ANSWER_LOG, bb.PLAN, bb.FRONTIER_GOAL, bb.MAP_FIELDS):
        board.register_key(key, access=Access.WRITE)
    board.set(bb.FRONTIER_GOAL, None)
    board.set(bb.MAP_FIELDS, MapFields())
    try:
        robot = (-1.0, 0.0, 0.0)
        size = 4
        frame = Observation(np.zeros((size, size, 3), np.uint8), np.zeros((size, size), np.float32),
                            np.full((size, size), -1, np.int32), (), Intrinsics(size, size, 2.0, 2.0, 2.0, 2.0),
                            np.eye(4), robot)
        board.set(bb.MAP, corridor_map())
        board.set(bb.OBSERVATION, frame)
        board.set(bb.BUDGET, 10)
        board.set(bb.ANSWER_LOG, AnswerLog())
        select = SelectFrontier(ExploreConfig(method="lfe"))
        select.tick_once()
        assert select.status == Status.SUCCESS
        assert "Bellman over learned R_A, D" in select.feedback_message
        plan = board.get(bb.PLAN)
        assert plan is not None and abs(plan.path_xy[-1][0]) > abs(robot[0])  # toward one of the open ends
        assert abs(plan.yaw) < 0.1 or abs(abs(plan.yaw) - np.pi) < 0.1  # looking along the corridor
    finally:
        py_trees.blackboard.Blackboard.clear()
