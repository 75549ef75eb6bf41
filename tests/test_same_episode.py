"""Same seed, same episode: whole episodes, digested, hold the robot's behaviour fixed.

Each EQA case runs a real episode (world process, Zenoh, the tree) and digests what it decided and
what the world's evaluator saw: every step's answer probabilities and relevance, the answer and
why, what was opened, the floor seen after every frame, the path driven. A digest that changes
means the robot now behaves differently for the same seed: that is either a bug in a change meant
to keep behaviour (a refactor), or an intended change, and then the shipped calibration is remade
and the digest here updated in the same commit. Timings, run ids and tick counts (which depend on
the machine's speed) are left out. Beside them: a scenario suite's first lines, and one episode
of the shipped calibration replayed against the scores the file holds.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import pytest

from agent.app.config import load_config
from agent.app.eval.calibrate import FULL_BUDGET
from agent.app.runtime.calibrations import SHIPPED_DIR
from agent.app.eval.robot_tabletop import run_robot
from agent.app.runtime.run import RunRequest, run_episode
from worlds.home import generate_home
from worlds.bus.session import free_tcp_endpoint
from worlds.scenario import make_scenario
from worlds.suite import suite_line

pytestmark = pytest.mark.slow

#: name -> (seed, settings, hidden question, digest of the episode)
EPISODES = {
    "semantic-conformal": (3, ["episode.budget=12"], False, "0f3a327d3505e2a3"),
    "fbe-entropy": (5, ["explore.method=fbe", "episode.budget=10", "stop.rule=entropy"], False, "ab9aa08d397ff9b7"),
    "lfe": (7, ["explore.method=lfe", "episode.budget=8", "stop.rule=budget"], False, "1f075f5d09d4aa87"),
    "hidden": (60, [], True, "b8cfa49a245f6a6c"),
}
#: A shipped calibration episode (the shortest of the first sixty) and the suite part it came from.
CALIBRATION, CALIBRATION_EPISODE, CALIBRATION_PART = "calibration-semantic-sim.json", "calib-0011", ("calib", 11)
#: tabletop task and variant -> digest of the robot's exploration (Table I's executor)
TABLETOP = {("recursive", 0): "6989fb555b6c3064", ("drawer-door", 1): "789384d7713301f8"}

_DECIDED = ("status", "reason", "failed_behaviour", "answer", "answer_detail", "steps", "step_scores",
            "prediction_set", "acts", "evaluation")
_TIMINGS = {"seconds", "wall_s", "planning_ms", "execution_s", "skill_seconds", "ticks", "startup_s"}


def _without_timings(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _without_timings(item) for key, item in value.items() if key not in _TIMINGS}
    if isinstance(value, list):
        return [_without_timings(item) for item in value]
    return value


def _digest(record: dict[str, Any]) -> str:
    text = json.dumps(_without_timings(record), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@pytest.mark.parametrize("name", sorted(EPISODES))
def test_an_eqa_episode_decides_as_it_always_has(name: str, tmp_path: Path) -> None:
    seed, settings, hidden, expected = EPISODES[name]
    scenario = make_scenario(generate_home(seed), seed, hidden=True).to_dict() if hidden else None
    listen = f'bus.listen=["{free_tcp_endpoint()}"]'  # beside any agent already on the default port
    result = run_episode(RunRequest(seed, load_config(None, [*settings, listen]), out_root=tmp_path, scenario=scenario,
                                    save_map=False))
    decided = {key: result[key] for key in _DECIDED}
    assert result["status"] == "answered", result["reason"]
    assert "contract_problems" not in result  # every key on the board as behaviours/blackboard.py says
    assert _digest(decided) == expected, json.dumps(_without_timings(decided))[:4000]


def test_suites_are_written_as_they_always_were() -> None:
    """The first lines of the calibration suite the shipped calibration was run on, digested."""
    lines = [json.dumps(suite_line(seed, "calib", index, hidden=False), ensure_ascii=False)
             for index, seed in enumerate(range(20000, 20003))]
    assert hashlib.sha256("\n".join(lines).encode()).hexdigest()[:16] == "5bd7cf8951607420"


def test_a_shipped_calibration_episode_scores_as_the_file_says(tmp_path: Path) -> None:
    """The conformal threshold q̂ stands on the shipped episodes' scores: replayed now, one of
    them must give the same answer probabilities and relevance at every step."""
    shipped = json.loads((SHIPPED_DIR / CALIBRATION).read_text())
    [episode] = [e for e in shipped["episodes"] if e["id"] == CALIBRATION_EPISODE]
    part, index = CALIBRATION_PART
    entry = suite_line(episode["seed"], part, index, hidden=False)  # the suite was made with --hidden never
    assert entry["id"] == episode["id"]
    listen = f'bus.listen=["{free_tcp_endpoint()}"]'
    result = run_episode(RunRequest(episode["seed"], load_config(None, [FULL_BUDGET, listen]), out_root=tmp_path,
                                    scenario=entry["scenario"], save_map=False))
    assert result["step_scores"] == episode["step_scores"]


@pytest.mark.parametrize("task, variant", sorted(TABLETOP))
def test_the_robot_explores_a_tabletop_as_it_always_has(task: str, variant: int) -> None:
    row = run_robot(task, variant)
    assert _digest(row) == TABLETOP[(task, variant)], json.dumps(_without_timings(row))[:4000]
