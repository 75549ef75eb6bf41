"""Running many episodes in parallel worker processes, appending each result as it finishes.

Each worker process starts one world child process of its own and resets it per episode, so a
world's start-up is paid once per worker, not once per episode (a world that ends fails the episode
it ended in, saying how, and the worker starts another for the next). Given running worlds instead
(``homebot world`` on other machines, each named by its Zenoh endpoint), one worker joins each of
them, so the same command spreads its episodes over several machines. On a Ray cluster (``--ray``)
each episode is instead a task that starts its own world on the node it lands on (or joins a listed
world that no other task is using), and Ray runs it again when its worker or node dies. Results go
to a JSON-lines file, one line per finished episode, flushed at once; a rerun skips the (scenario,
variant) pairs already in the file, so an interrupted evaluation loses nothing and redoes nothing.
"""

from __future__ import annotations

import atexit
import functools
import json
import logging
import multiprocessing
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from worlds.bus.keys import check_namespace
from worlds.bus.liveness import describe_exit
from worlds.bus.session import check_endpoint, free_tcp_endpoint
from agent.app.config import Config, load_config
from agent.app.progress import ProgressLine
from agent.app.runtime.episode_bus import EpisodeBus
from agent.app.runtime import interrupt, ray_backend
from agent.app.runtime.pool import in_processes, quiet_worker
from agent.app.runtime.run import RunError, RunRequest, run_episode
from agent.app.runtime.world_process import WorldProcess, WorldStartError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class WorldAddress:
    """A running world to join: its Zenoh endpoint and the namespace it serves under."""

    endpoint: str
    namespace: str = "homebot/default"

    @classmethod
    def parse(cls, text: str) -> WorldAddress:
        """Read a world's address as the command line gives it.

        Args:
            text: ``tcp/host:port`` or ``namespace@tcp/host:port``.

        Returns:
            The address, under ``homebot/default`` when no namespace is given.

        Raises:
            ValueError: a malformed endpoint or namespace, named.
        """
        namespace, sep, endpoint = text.strip().rpartition("@")
        return cls(check_endpoint(endpoint), check_namespace(namespace) if sep else "homebot/default")


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
        """(entry id, variant): what a results line is known by, so a rerun skips it."""
        return (self.entry_id, self.variant)


def finished_keys(path: Path) -> set[tuple[str, str]]:
    """The jobs a results file holds already, so a rerun can skip them.

    Args:
        path: a results file (JSON lines); it need not exist.

    Returns:
        The (entry id, variant) pairs of its whole lines (a torn last line is ignored).
    """
    return {(result["id"], result["variant"]) for result in read_results(path)}


def read_results(path: Path) -> list[dict[str, Any]]:
    """Every result a results file holds, in file order.

    Args:
        path: a results file (JSON lines); a missing file holds none.

    Returns:
        The whole lines, parsed; a torn line from an interrupted run is skipped.
    """
    results = []
    for line in path.read_text(encoding="utf-8").splitlines() if path.exists() else []:
        try:
            results.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return results


def run_jobs(jobs: list[Job], results_path: Path, workers: int, base_config: Config,
             progress: Callable[[int, int, dict[str, Any]], None] | None = None,
             worlds: list[WorldAddress] | None = None, recordings: Path | None = None,
             ray: str | None = None) -> int:
    """Run the jobs not yet in ``results_path``, appending each result as it ends.

    Args:
        jobs: the episodes to run.
        results_path: the results file (JSON lines), created or appended to.
        workers: how many worker processes, each starting its own world; ignored with ``worlds``;
            with ``ray``, the episodes at once on a Ray cluster started here.
        base_config: the settings every job's overrides apply to.
        progress: called after each episode with (done, of how many, its result).
        worlds: running worlds to join instead, one worker each.
        recordings: where to keep each episode's run folder with its Rerun recording
            (``<recordings>/<id>-<variant>/recording.rrd``); None keeps no recording.
        ray: run each episode as a Ray task (`ray_backend.LOCAL`: on a cluster started here,
            else on the one at this address; None: worker processes here). A task starts its own
            world on the node it lands on (`run_in_own_world`), declaring ``ray.cpus_per_episode``
            CPUs; with ``worlds``, it joins one no other task is using (`run_in_world`), declaring
            ``ray.cpus_per_agent``, so that as many episodes run at once as there are worlds.

    Returns:
        How many jobs ran now (0 when the file held them all).
    """
    done = finished_keys(results_path)
    todo = [job for job in jobs if job.key not in done]
    results_path.parent.mkdir(parents=True, exist_ok=True)
    if not todo:
        return 0
    calls = [(job, base_config, recordings.resolve() if recordings else None) for job in todo]
    if ray is not None:
        function, cpus = ((run_in_world, base_config.ray.cpus_per_agent) if worlds else
                          (run_in_own_world, base_config.ray.cpus_per_episode))
        finished = ray_backend.as_finished(function, calls, ray, cpus, len(worlds) if worlds else workers,
                                           worlds or None)
    else:
        addresses = multiprocessing.get_context("spawn").Queue()
        for address in worlds or []:
            addresses.put(address)
        finished = in_processes(_run_job, calls, len(worlds) if worlds else workers, _start_worker_world,
                                (base_config, addresses if worlds else None))
    append_results(results_path, finished, len(todo), progress)
    return len(todo)


def append_results(path: Path, finished: Iterator[tuple[Any, dict[str, Any]]], total: int,
                   progress: Callable[[int, int, dict[str, Any]], None] | None = None) -> None:
    """Append each result to a results file as its call finishes, one JSON line flushed at once, so
    that a run stopped at any point keeps every whole line (and a torn one from before is cut).

    Args:
        path: the results file (JSON lines), created or appended to.
        finished: (arguments, result) as each call finishes (`agent.app.runtime.pool.as_finished`);
            closed when this returns or raises, so that the calls not finished are cancelled.
        total: the calls in all, for ``progress``.
        progress: called after each result with (done, ``total``, the result).
    """
    _repair_torn_tail(path)
    with closing(finished), open(path, "a", encoding="utf-8") as out:
        for done, (_, result) in enumerate(finished, start=1):
            out.write(json.dumps(result, ensure_ascii=False) + "\n")
            out.flush()
            if progress:
                progress(done, total, result)
            interrupt.check()  # a Ctrl-C lost while the result came in


def stderr_progress(started: float) -> Callable[[int, int, dict[str, Any]], None]:
    """A progress line on stderr (`agent.app.progress`) after each episode, with the time left at the
    pace so far.

    Args:
        started: `time.monotonic` when the episodes began.

    Returns:
        A ``progress`` callback for `run_jobs`.
    """
    line = ProgressLine()

    def progress(done: int, total: int, result: dict[str, Any]) -> None:
        rate = (time.monotonic() - started) / done
        line.show(f"{done}/{total} episodes, last {result['variant']} {result['id']} ({result['status']}), "
                  f"about {rate * (total - done) / 60:.1f} min left", done == total)

    return progress


def results_for(jobs: list[Job], results_path: Path) -> list[dict[str, Any]]:
    """The results of exactly these jobs, for a report over them.

    Args:
        jobs: the jobs whose results are wanted.
        results_path: the results file.

    Returns:
        Their results in the jobs' order; jobs without a line are left out, and other lines ignored.
    """
    by_key = {(r["id"], r["variant"]): r for r in read_results(results_path)}
    return [by_key[job.key] for job in jobs if job.key in by_key]


#: The fields of a result line that time the episode: the one thing two runs of a job may differ in.
TIMING_FIELDS = ("seconds",)


def comparable(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Results as two runs of the same jobs must give them, whichever ran them and in whatever order:
    by (entry id, variant), without `TIMING_FIELDS`.

    Args:
        results: result lines.

    Returns:
        The same lines, sorted, the timing left out.
    """
    return sorted(({key: value for key, value in result.items() if key not in TIMING_FIELDS} for result in results),
                  key=lambda result: (result["id"], result["variant"]))


def _repair_torn_tail(path: Path) -> None:
    """Cut a half-written last line left by an interrupted run, so appends start on a new line."""
    if path.exists() and path.stat().st_size:
        text = path.read_text(encoding="utf-8")
        if not text.endswith("\n"):
            path.write_text(text[: text.rfind("\n") + 1], encoding="utf-8")


@dataclass(frozen=True)
class WorkerWorld:
    """The world a worker process runs its episodes in: a listed running world it joined, or a
    world child process of its own that stops when the worker exits.

    Attributes:
        namespace: the key prefix the world serves under.
        endpoint: the Zenoh endpoint the world listens on.
        scratch: where the worker's episodes put their run folders.
        process: the world child process of its own; None for a world it joined.
        number: which of the worker's own worlds it is (another starts when one has ended).
    """

    namespace: str
    endpoint: str
    scratch: Path
    process: WorldProcess | None = None
    number: int = 1


#: This process's world while it is a pool worker of `run_jobs`: set once by the pool's initializer
#: (`_start_worker_world`), read by each job (`_run_job`), None in any other process. A process
#: pool hands what its initializer made to the jobs in no other way.
_worker_world: WorkerWorld | None = None


def _start_worker_world(config: Config, addresses: Any | None) -> None:
    """Worker initialiser: join the next listed world, or start a world child process for this
    worker that stops when it exits; either becomes this process's `WorkerWorld`."""
    global _worker_world
    quiet_worker()
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    scratch = Path(tempfile.mkdtemp(prefix="homebot-eval-world-"))
    if addresses is not None:
        address: WorldAddress = addresses.get(timeout=10)
        _worker_world = WorkerWorld(address.namespace, address.endpoint, scratch)
        return
    _worker_world = _own_world(config, f"homebot/eval-{os.getpid()}", scratch, 1)


def _own_world(config: Config, namespace: str, scratch: Path, number: int) -> WorkerWorld:
    """The worker's ``number``-th world child process, stopped when the worker exits; its log is
    ``world.log`` in ``scratch``, the next ones' ``world-2.log``, …"""
    endpoint = free_tcp_endpoint()
    world = WorldProcess(namespace, endpoint, config.camera,
                         scratch / ("world.log" if number == 1 else f"world-{number}.log"),
                         zenoh_config=config.bus.zenoh_config)
    atexit.register(world.stop)
    return WorkerWorld(namespace, endpoint, scratch, world, number)


def _live_world(config: Config) -> WorkerWorld:
    """This worker's world; when its own world has ended (the episode it ended in failed, saying
    how), another is started, so that one world's end does not fail every episode left."""
    global _worker_world
    world = _worker_world
    if world is None:
        raise RuntimeError("_run_job runs in a worker of run_jobs, whose initializer gives it its world")
    code = world.process.process.poll() if world.process is not None else None
    if code is not None:
        log.warning("this worker's world ended (%s; its log: %s); starting another", describe_exit(code),
                    world.process.log_path)
        world = _worker_world = _own_world(config, world.namespace, world.scratch, world.number + 1)
    return world


def _run_job(job: Job, base_config: Config, recordings: Path | None = None) -> dict[str, Any]:
    """One episode in this pool worker's world (`_live_world`)."""
    return _episode_record(job, base_config, recordings, _live_world(base_config))


def run_in_own_world(job: Job, base_config: Config, recordings: Path | None = None) -> dict[str, Any]:
    """One episode with a world of its own, started beside it and stopped when it ends, in any
    process: a Ray task's, on whichever node it lands. The world also ends if this process is
    killed (`WorldProcess`), so that a task Ray ends or runs again leaves none behind.

    Args:
        job: the episode.
        base_config: the settings the job's overrides apply to.
        recordings: where to keep its run folder with its Rerun recording (None: none kept).

    Returns:
        Its result line; any failure is a result with its reason, never a crash.
    """
    return _episode_record(job, base_config, recordings, None)


def run_in_world(job: Job, base_config: Config, recordings: Path | None, world: WorldAddress) -> dict[str, Any]:
    """One episode in a running world that no other episode uses meanwhile, from any process: a Ray
    task's, on whichever node it lands (`run_jobs` hands each world to one task at a time).

    Args:
        job: the episode.
        base_config: the settings the job's overrides apply to.
        recordings: where to keep its run folder with its Rerun recording (None: none kept).
        world: the world to join.

    Returns:
        Its result line; any failure is a result with its reason, never a crash.
    """
    return _episode_record(job, base_config, recordings, WorkerWorld(world.namespace, world.endpoint, _scratch()))


@functools.cache
def _scratch() -> Path:
    """Where this process's episodes with worlds of their own put their run folders, world logs among them."""
    return Path(tempfile.mkdtemp(prefix="homebot-eval-"))


def _episode_record(job: Job, base_config: Config, recordings: Path | None, world: WorkerWorld | None
                    ) -> dict[str, Any]:
    """One episode in ``world`` (None: a world of its own), its run folder (and recording) kept under
    ``recordings`` when given; any failure is a result with its reason, never a crash."""
    started = time.monotonic()
    config = load_config(overrides=list(job.overrides), base=base_config)
    request = RunRequest(seed=job.seed, config=config, out_root=recordings or (world.scratch if world else _scratch()),
                         connect=world.endpoint if world else None,
                         namespace=world.namespace if world else f"homebot/eval-{os.getpid()}",
                         run_id=f"{job.entry_id}-{job.variant}", scenario=job.scenario, save_map=False,
                         record=recordings is not None)
    joined = world.process if world else None  # the worker's own world, which may still be starting
    try:
        if joined is not None:
            joined.wait_listening(config.bus.world_start_timeout_s)
        bus = EpisodeBus.open(request)
        if joined is not None:
            bus.follow(joined)
        result = run_episode(request, bus=bus)
    except (RunError, WorldStartError) as error:
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
        "acts": result.get("acts", []),
        "evaluation": _evaluation_summary(result.get("evaluation")),
        "seconds": round(time.monotonic() - started, 2),
    }


def _evaluation_summary(evaluation: dict[str, Any] | None) -> dict[str, Any] | None:
    """The world's episode report without the room outlines, which only pictures need."""
    return None if evaluation is None else {key: value for key, value in evaluation.items() if key != "rooms"}
