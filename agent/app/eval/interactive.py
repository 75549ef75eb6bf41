"""`homebot eval interactive`: RoboEXP's Table I over the five tabletop tasks.

Each variant of each task is explored until nothing is left unexplored, and the explored
action-conditioned scene graph is compared with the scene's ground truth: success (the graphs
match), object recovery (hidden objects found), state recovery (the scene put back as it was),
unexplored space, and graph edit distance. Results are appended per scene and a rerun resumes.

The executor says what perceives and acts:
- ``symbolic``: the symbolic tabletop of `agent.acsg.symbolic`, i.e. perfect perception and skills
  that never fail. It measures the decision logic and the action stack alone: an upper bound for
  the robot, and the reference a robot run is read against.
- ``robot``: the robot in PyBullet (`agent.app.eval.robot_tabletop`): head and wrist cameras fused in
  the instance memory, the arm skills planned from them. Scenes run in ``workers`` processes,
  each with its own world.

Which seeds run is a range per task (``variants`` from ``seed_base``), or one of the fixed splits of
`worlds.tabletop_splits.SPLITS` (`split_seeds`): the tuning seeds, traced and tuned on, and the reported
ones, run whole for the table and never traced. Besides Table I's columns, the report counts every
failure by cause (`agent.app.eval.failure_causes`), and keeps both in ``interactive-report.json``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from agent.acsg.decision import RuleDecisionModule
from agent.acsg.interactive_exploration import explore
from agent.acsg.json_format import from_ground_truth
from agent.acsg.metrics import episode_metrics, mean_and_sem
from agent.acsg.symbolic import SymbolicScene
from agent.app.eval.failure_causes import cause_table
from agent.app.eval.runner import append_results, read_results
from agent.app.eval.tabletop_recording import record_graph
from agent.app.progress import counted
from agent.app.runtime.pool import as_finished
from worlds.tabletop import TASKS, VARIANTS, tabletop_variant
from worlds.tabletop_splits import SPLITS

EXECUTORS = ("symbolic", "robot")
#: Success rates of RoboEXP's Table I, per task, for the table printed beside ours.
PAPER_SUCCESS = {"drawer-only": 0.9, "door-only": 0.9, "drawer-door": 0.7, "recursive": 0.7, "occlusion": 0.5}
COLUMNS = ("success", "object_recovery", "state_recovered", "unexplored_space", "graph_edit_distance")


def run_symbolic(task: str, seed: int, recording: Path | None = None) -> dict[str, Any]:
    """Explore one tabletop variant with the symbolic executor; its Table I metrics.

    Args:
        task: the tabletop task.
        seed: the variant's seed.
        recording: a folder to write the explored graph's Rerun recording into, or None.

    Returns:
        The metrics, with the seconds taken.
    """
    scene = tabletop_variant(task, seed)
    world = SymbolicScene.from_tabletop(scene)
    started = time.monotonic()
    result = explore(world, RuleDecisionModule(), world)
    if recording is not None:
        record_graph(recording, f"{task}-{seed}-symbolic", result.graph)
    metrics = episode_metrics(result.graph, from_ground_truth(scene.ground_truth_acsg()), world.start_positions(),
                              world.positions(), world.start_part_states(), world.part_states())
    return {**asdict(metrics), "actions": len(result.steps()), "returned_to_start": result.returned_to_start,
            "seconds": round(time.monotonic() - started, 3)}


def run_scene(executor: str, task: str, seed: int, recordings: Path | None = None) -> dict[str, Any]:
    """One result row: the scene explored by ``executor``.

    Args:
        executor: "robot" or "symbolic".
        task: the tabletop task.
        seed: the variant's seed.
        recordings: where to keep each scene's recording (``<recordings>/<task>-<seed>-<executor>/``), or None.

    Returns:
        The row.
    """
    if executor == "robot":
        from agent.app.eval.robot_tabletop import run_robot  # PyBullet and the arm only when asked for

    folder = recordings / f"{task}-{seed}-{executor}" if recordings is not None else None
    if executor == "robot":
        metrics = run_robot(task, seed, folder)
    else:
        metrics = run_symbolic(task, seed, folder)
    return {"task": task, "seed": seed, "executor": executor, **metrics}


def split_seeds(split: str | None, variants: int | None, seed_base: int | None,
                record: bool = False) -> tuple[int, int]:
    """The first seed and the variants per task that the evaluation's options ask for.

    Without a split, ``seed_base`` (default 0) and ``variants`` (default the tuning split's) say
    the range; such a range may not reach into the reported split's seeds, which run only as that
    split. A split gives its own range, of which ``variants`` may take the first few.

    Args:
        split: a name of `worlds.tabletop_splits.SPLITS`, or None.
        variants: variants per task, or None for the default.
        seed_base: the first seed, or None for the default; not with a split.
        record: whether each scene is to be recorded (never for the reported split: no one traces it).

    Returns:
        (seed_base, variants).

    Raises:
        ValueError: an unknown split, a range that conflicts with it, or a bad number, naming the option.
    """
    if split is not None:
        if split not in SPLITS:
            raise ValueError(f"--split: {split!r} is not one of {', '.join(SPLITS)}")
        chosen = SPLITS[split]
        if seed_base is not None:
            raise ValueError(f"--seed-base: the {split} split starts at {chosen.seed_base}; "
                             "give a split or a seed base")
        if variants is not None and not 1 <= variants <= chosen.variants:
            raise ValueError(f"--variants: {variants} must be 1..{chosen.variants} for the {split} split")
        if record and split == "reported":
            raise ValueError("--record: the reported split is run whole for the table, never traced")
        return chosen.seed_base, variants if variants is not None else chosen.variants
    base = 0 if seed_base is None else seed_base
    count = VARIANTS if variants is None else variants
    if base < 0:
        raise ValueError(f"--seed-base: {base} must be 0 or more")
    if count < 1:
        raise ValueError(f"--variants: {count} must be at least 1")
    reported = SPLITS["reported"].seeds()
    if base < reported.stop and reported.start < base + count:
        raise ValueError(f"--seed-base: seeds {base}..{base + count - 1} reach into the reported split "
                         f"({reported.start}..{reported.stop - 1}); run it as --split reported")
    return base, count


def evaluate_interactive(out_dir: Path, tasks: Iterable[str] = TASKS, variants: int = VARIANTS,
                         executor: str = "symbolic",
                         progress: Callable[[int, int, dict[str, Any]], None] | None = None,
                         workers: int = 1, recordings: Path | None = None, seed_base: int = 0,
                         ray: str | None = None) -> dict[str, Any]:
    """Run the scenes not yet in ``<out_dir>/interactive-results.jsonl``; return the per-task table.

    The table and the failure causes are also written to ``<out_dir>/interactive-report.json``.

    Args:
        out_dir: where the results and the table go.
        tasks: the tabletop tasks.
        variants: the variants per task: seeds ``seed_base`` .. ``seed_base + variants - 1``.
        executor: "symbolic" or "robot".
        progress: called with (done, total, row) after each scene, if given.
        workers: scenes run at once.
        recordings: where to keep each scene's Rerun recording of its explored graph, or None.
        seed_base: the first variant's seed.
        ray: run each scene as a Ray task of one CPU (`agent.app.runtime.pool.as_finished`):
            `ray_backend.LOCAL` or a cluster's address; None: in worker processes here.

    Returns:
        The table, the failure causes (`failure_causes.cause_table`, as JSON), the seeds, the
        results file and the scene count.

    Raises:
        ValueError: an unknown task or executor, or a bad count.
    """
    tasks = list(tasks)
    unknown = sorted(set(tasks) - set(TASKS))
    if unknown:
        raise ValueError(f"--tasks: unknown {', '.join(unknown)} (known: {', '.join(TASKS)})")
    if executor not in EXECUTORS:
        raise ValueError(f"--executor: {executor!r} is not one of {', '.join(EXECUTORS)}")
    if variants < 1:
        raise ValueError(f"--variants: {variants} must be at least 1")
    if seed_base < 0:
        raise ValueError(f"--seed-base: {seed_base} must be 0 or more")
    if workers < 1:
        raise ValueError(f"--workers: {workers} must be at least 1")
    seeds = range(seed_base, seed_base + variants)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "interactive-results.jsonl"
    done = {(r["task"], r["seed"], r["executor"]) for r in read_results(path)}
    todo = [(task, seed) for task in tasks for seed in seeds if (task, seed, executor) not in done]
    recordings = recordings.resolve() if recordings is not None else None  # a Ray task may run in another folder
    calls = [(executor, task, seed, recordings) for task, seed in todo]  # scenes in processes of their own
    append_results(path, as_finished(run_scene, calls, workers, ray), len(todo), progress)
    wanted = {(task, seed) for task in tasks for seed in seeds}
    rows = [r for r in read_results(path) if r["executor"] == executor and (r["task"], r["seed"]) in wanted]
    report = {"executor": executor, "seeds": [seeds.start, seeds.stop - 1], "n": len(rows),
              "table": table(rows, tasks), "causes": {c: n.to_dict() for c, n in cause_table(rows).items()}}
    (out_dir / "interactive-report.json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    return {**report, "results": str(path)}


def table(rows: list[dict[str, Any]], tasks: list[str]) -> dict[str, dict[str, tuple[float, float]]]:
    """Task -> column -> (mean, standard error over the variants).

    Args:
        rows: the scenes' results.
        tasks: the tasks, in the table's order.

    Returns:
        The table.
    """
    return {task: {column: mean_and_sem(float(r[column]) for r in rows if r["task"] == task) for column in COLUMNS}
            for task in tasks if any(r["task"] == task for r in rows)}


def scene_progress() -> Callable[[int, int, dict[str, Any]], None]:
    """A progress line on stderr (`agent.app.progress`): the scenes done and how the last one went.

    Returns:
        A ``progress`` callback for `evaluate_interactive`.
    """
    return counted("scenes", lambda row: f"{row['task']} {row['seed']}: "
                   f"{'success' if row['success'] else 'failed'}, GED {row['graph_edit_distance']:g}")
