"""The exploration methods of the coverage task: one planning step, each chooser, the evaluation."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from agent.app.eval.coverage import SIZES, evaluate_coverage, format_table, jobs, model_digest, plot_curves
from agent.lfe.bellman import choose_frontier, plan
from agent.app.bench.lfe import branches
from agent.lfe.coverage import fbe_near, run_coverage
from agent.lfe.estimator import LearnedEstimator
from agent.lfe.methods import Method, make_chooser
from agent.lfe.model import FrontierUNet, UNetConfig, save_model
from agent.lfe.task import CoverageConfig, TrueHome
from agent.mapping.grid import GridSpec
from worlds.home import generate_home

OPEN = GridSpec((0.0, 0.0), 1.0, (1, 40))  # a straight corridor of 1 m cells: distances are column gaps


pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.fixture(scope="module")
def model_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An untrained, fixed network: its estimates are arbitrary but repeatable."""
    torch.manual_seed(0)
    config = UNetConfig(base_channels=4, depth=3)
    path = tmp_path_factory.mktemp("model") / "unet.pt"
    save_model(path, FrontierUNet(config), config, {})
    return path


@pytest.fixture(scope="module")
def small_home() -> TrueHome:
    return TrueHome.from_home(generate_home(27), CoverageConfig(), seed=27)  # 76 m², four rooms


def corridor_step(area: list[float], columns: list[int], sigma: float, robot: int = 0):
    """choose_frontier with the robot at column ``robot`` of `OPEN`, frontiers at ``columns``, D_in = D_out = 1 m."""
    traversable = np.ones(OPEN.shape, dtype=bool)
    ones = [1.0] * len(area)
    return choose_frontier(area, ones, ones, OPEN, traversable, (0, robot), [(0, c) for c in columns], sigma,
                           step_length_m=1.0, steps_per_move=1.0)


def test_a_planning_step_plans_over_the_six_largest_and_answers_in_full_indices() -> None:
    area = [1.0, 50.0, 2.0, 40.0, 3.0, 30.0, 20.0, 10.0]  # the two smallest are left out
    step = corridor_step(area, [1, 30, 2, 25, 3, 20, 15, 10], sigma=200.0)
    planned = ~np.isnan(step.q_values)
    assert planned.tolist() == [False, True, False, True, True, True, True, True]
    assert step.value == pytest.approx(sum(sorted(area)[2:]))  # time for all six: every area is won
    assert set(step.sequence) == {1, 3, 4, 5, 6, 7}


def test_a_planning_step_agrees_with_the_recursion_on_the_distances_it_computes() -> None:
    area, columns, sigma = [10.0, 30.0, 5.0], [4, 12, 2], 20.0
    step = corridor_step(area, columns, sigma)
    cells = [0, *columns]
    distances = np.abs(np.subtract.outer(cells, cells)).astype(float)
    direct = plan(area, [1.0] * 3, [1.0] * 3, distances, sigma)
    assert step.choice == direct.choice and step.value == pytest.approx(direct.value)
    np.testing.assert_allclose(step.q_values, direct.q_values)


def test_the_steps_left_decide_between_a_small_frontier_behind_and_a_large_one_ahead() -> None:
    area, columns = [5.0, 100.0], [8, 35]  # the robot at column 10: 2 m back, or 25 m on
    assert corridor_step(area, columns, sigma=10.0, robot=10).choice == 0  # the large one is out of reach
    assert corridor_step(area, columns, sigma=27.0, robot=10).choice == 1  # time for it, not for a detour first
    with_time = corridor_step(area, columns, sigma=200.0, robot=10)
    assert with_time.choice == 0 and with_time.value == pytest.approx(105.0)  # both: the near one on the way


def test_methods_need_what_they_plan_with() -> None:
    home = TrueHome.from_home(generate_home(27), CoverageConfig(), seed=27)
    assert make_chooser("fbe-near", home, None) is fbe_near
    for method in ("lfe", "greedy"):
        with pytest.raises(ValueError, match=f"method '{method}' needs a trained estimator"):
            make_chooser(method, home, None)
    with pytest.raises(ValueError, match="'nearest' is not a valid Method"):
        make_chooser("nearest", home, None)


@pytest.mark.parametrize("method", list(Method))
def test_every_method_explores_a_home(method: Method, small_home: TrueHome, model_path: Path) -> None:
    config = CoverageConfig(budget_steps=60)
    estimator = LearnedEstimator.load(model_path)
    chosen: list[tuple[int, int]] = []
    result = run_coverage(small_home, make_chooser(method, small_home, estimator, config), config,
                          on_plan=lambda situation, index: chosen.append((index, len(situation.frontiers))))
    assert chosen and all(0 <= index < count for index, count in chosen)
    assert result.coverage[-1] > result.coverage[0] + 0.1  # sixty steps see a good part of 76 m²
    assert (np.diff(result.coverage) >= 0).all()


def test_the_oracle_covers_a_large_home_at_least_as_well_as_the_nearest_frontier() -> None:
    config = CoverageConfig(budget_steps=150)
    home = TrueHome.from_home(generate_home(2, area_m2=250.0), config, seed=2)
    nearest = run_coverage(home, make_chooser("fbe-near", home, None, config), config).coverage[-1]
    oracle = run_coverage(home, make_chooser("lfe-oracle", home, None, config), config).coverage[-1]
    assert oracle >= nearest - 0.02, (oracle, nearest)


def test_branches_count_the_full_recursion() -> None:
    assert [branches(n) for n in (1, 2, 3)] == [1, 4, 15]
    assert branches(6) == branches(9) == 1956  # only six frontiers are planned over


def test_jobs_cover_every_size_and_method_with_seeds_apart_from_training() -> None:
    planned = jobs(2, ["fbe-near", "lfe"])
    assert len(planned) == 2 * 2 * len(SIZES)
    assert {job.size for job in planned} == set(SIZES)
    assert len({job.seed for job in planned}) == 2 * len(SIZES)
    assert min(job.seed for job in planned) >= 1_000_000


def test_the_evaluation_appends_resumes_and_tabulates(tmp_path: Path) -> None:
    seen: list[dict] = []
    report = evaluate_coverage(tmp_path, 1, ["fbe-near"], steps=20, progress=lambda done, total, row: seen.append(row))
    assert report["n"] == len(seen) == len(SIZES)
    rows = [json.loads(line) for line in (tmp_path / "coverage-results.jsonl").read_text().splitlines()]
    assert [r["size"] for r in rows] == list(SIZES)
    assert all(0 < r["coverage"] <= 100 and r["budget"] == 20 and len(r["curve"]) == 3 for r in rows)
    again: list[dict] = []
    report = evaluate_coverage(tmp_path, 1, ["fbe-near"], steps=20, progress=lambda *args: again.append(args))
    assert again == [] and report["n"] == len(SIZES)  # nothing run twice
    table = report["table"]["fbe-near"]
    assert set(table) == {*SIZES, "overall"}
    assert table["overall"][0] == pytest.approx(np.mean([r["coverage"] for r in rows]))
    text = format_table(report["table"])
    assert "| fbe-near |" in text and "92.7 / 74.8 / 61.0 / 76.8" in text
    assert plot_curves(report["rows"], ["fbe-near"], tmp_path / "curves.png").stat().st_size > 0


def test_learned_rows_of_another_network_are_run_again_not_mixed_in(tmp_path: Path) -> None:
    planned = jobs(1, ["fbe-near", "greedy"], model="abc")
    assert {(job.method, job.model) for job in planned} == {("fbe-near", None), ("greedy", "abc")}
    stale = [{"size": size, "seed": job.seed, "method": "greedy", "budget": 5, "model": "0123456789ab",
              "coverage": 1.0, "curve": [1.0]} for size, job in zip(SIZES, [j for j in planned if j.model])]
    (tmp_path / "coverage-results.jsonl").write_text("".join(json.dumps(row) + "\n" for row in stale))
    ran: list[dict] = []
    report = evaluate_coverage(tmp_path, 1, ["greedy"], steps=5, progress=lambda done, total, row: ran.append(row))
    assert len(ran) == len(SIZES)  # the stale rows were another network's
    assert {row["model"] for row in report["rows"]} == {model_digest(None)}


@pytest.mark.parametrize("arguments, message", [
    ({"methods": ["fbe-near", "random"]}, "--methods: unknown random"),
    ({"homes_per_size": 0}, "--homes: 0 must be at least 1"),
    ({"workers": 0}, "--workers: 0 must be at least 1"),
    ({"steps": 0}, "--steps: 0 must be at least 1"),
    ({"model": Path("no-such-model.pt")}, "--model: no-such-model.pt is not a file"),
])
def test_bad_evaluation_arguments_are_refused(tmp_path: Path, arguments: dict, message: str) -> None:
    options = {"homes_per_size": 1, "methods": ["fbe-near"], **arguments}
    with pytest.raises(ValueError, match=message):
        evaluate_coverage(tmp_path, **options)
    assert not (tmp_path / "coverage-results.jsonl").exists()
