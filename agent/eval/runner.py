"""Running many episodes in parallel worker processes, appending each result as it finishes.

Each worker process starts one world child process of its own and resets it per episode, so a
world's start-up is paid once per worker, not once per episode. Results go to a JSON-lines file,
one line per finished episode, flushed at once; a rerun skips the (scenario, variant) pairs already
in the file, so an interrupted evaluation loses nothing and redoes nothing.
"""

from __future__ import annotations

import atexit
import json
import logging
import multiprocessing
import os
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agent.bus.session import free_tcp_endpoint
from agent.config import Config, load_config
from agent.runtime.run import RunError, RunRequest, run_episode
from agent.runtime.world_process import WorldProcess

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Job:
    """One episode to run: a suite entry under one variant (a method, a stopping rule…)."""

    entry_id: str
    variant: str
    seed: int
    scenario: dict[str, Any]
    overrides: tuple[str, ...]  # config overrides that make the variant, e.g. explore.method=fbe

    @property
    def key(self) -> tuple[str, str]:
        return (self.entry_id, self.variant)


def finished_keys(path: Path) -> set[tuple[str, str]]:
    """The (entry id, variant) pairs already in a results file (a torn last line is ignored)."""
    return {(result["id"], result["variant"]) for result in read_results(path)}


def read_results(path: Path) -> list[dict[str, Any]]:
    """Every whole result line of a results file; a torn line from an interrupted run is skipped."""
    results = []
    for line in path.read_text(encoding="utf-8").splitlines() if path.exists() else []:
        try:
            results.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return results


def run_jobs(jobs: list[Job], results_path: Path, workers: int, base_config: Config,
             progress: Callable[[int, int, dict[str, Any]], None] | None = None) -> int:
    """Run the jobs not yet in ``results_path``; return how many ran now."""
    done = finished_keys(results_path)
    todo = [job for job in jobs if job.key not in done]
    results_path.parent.mkdir(parents=True, exist_ok=True)
    if not todo:
        return 0
    _repair_torn_tail(results_path)
    context = multiprocessing.get_context("spawn")
    with open(results_path, "a", encoding="utf-8") as out, ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=_start_worker_world, initargs=(base_config,)
    ) as pool:
        pending = {pool.submit(_run_job, job, base_config) for job in todo}
        finished = 0
        while pending:
            complete, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in complete:
                result = future.result()
                out.write(json.dumps(result, ensure_ascii=False) + "\n")
                out.flush()
                finished += 1
                if progress:
                    progress(finished, len(todo), result)
    return len(todo)


def _repair_torn_tail(path: Path) -> None:
    """Cut a half-written last line left by an interrupted run, so appends start on a new line."""
    if path.exists() and path.stat().st_size:
        text = path.read_text(encoding="utf-8")
        if not text.endswith("\n"):
            path.write_text(text[: text.rfind("\n") + 1], encoding="utf-8")


_WORKER: dict[str, Any] = {}


def _start_worker_world(config: Config) -> None:
    """Worker initialiser: one world child process for this worker, stopped when it exits."""
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    namespace = f"homebot/eval-{os.getpid()}"
    endpoint = free_tcp_endpoint()
    log_dir = Path(tempfile.mkdtemp(prefix="homebot-eval-world-"))
    world = WorldProcess(namespace, endpoint, config.camera, log_dir / "world.log")
    atexit.register(world.stop)
    _WORKER.update(namespace=namespace, endpoint=endpoint, world=world, scratch=log_dir)


def _run_job(job: Job, base_config: Config) -> dict[str, Any]:
    """One episode in this worker's world; any failure is a result with its reason, never a crash."""
    started = time.monotonic()
    config = load_config(overrides=list(job.overrides), base=base_config)
    request = RunRequest(seed=job.seed, config=config, out_root=_WORKER["scratch"], connect=_WORKER["endpoint"],
                         namespace=_WORKER["namespace"], run_id=f"{job.entry_id}-{job.variant}",
                         scenario=job.scenario, save_map=False)
    try:
        result = run_episode(request)
    except RunError as error:
        result = {"status": "failed", "reason": str(error), "step_scores": []}
    return {
        "id": job.entry_id,
        "variant": job.variant,
        "seed": job.seed,
        "kind": job.scenario.get("kind"),
        "question": job.scenario["question"],
        "ground_truth": job.scenario["answer"],
        "budget": result.get("budget", job.scenario["budget"]),
        "status": result["status"],
        "reason": result.get("reason"),
        "answer": result.get("answer"),
        "steps": result.get("steps", 0),
        "step_scores": result.get("step_scores", []),
        "seconds": round(time.monotonic() - started, 2),
    }
