"""`homebot bench eval`: how many evaluation episodes a minute the local process pool and a Ray
cluster run, with 1 and 2 workers, and whether both give the same records.

The episodes are full-budget calibration episodes (`agent.app.eval.calibrate.full_budget_jobs`)
of a small suite made for the bench, with no hidden evidence and a short step budget, so that the
figure is dominated by what a lab's evaluation spends its time on: an agent and its world stepping
through an episode, and the start-up each backend pays around it. For Ray the local cluster's own
start is timed apart from the episodes (a cluster that is up already, as on a lab's machines, does
not pay it per command).
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from agent.app.config import load_config
from agent.app.eval.calibrate import full_budget_jobs
from agent.app.eval.runner import comparable, read_results, run_jobs
from agent.app.runtime import ray_backend
from worlds.suite import plan_split, write_suite

#: The bench suite's first seed: homes no other suite of the tests or docs starts from.
SEED_BASE = 74000


def bench_eval(episodes: int, budget: int, workers: Sequence[int], with_ray: bool,
               progress: Callable[[str], None]) -> dict[str, Any]:
    """Run the same episodes on each backend with each number of workers; the rate of each.

    Args:
        episodes: the suite's entries, one episode each.
        budget: each episode's step budget.
        workers: the worker counts to measure.
        with_ray: measure a local Ray cluster too (it needs the ray package).
        progress: called with a line after each run.

    Returns:
        The report: one row per (backend, workers) with the seconds, the cluster's start (Ray),
        and the episodes per minute with and without it; and whether every run's records agree.
    """
    config = load_config(overrides=["bus.listen=[]", f"episode.budget={budget}"])
    rows: list[dict[str, Any]] = []
    records: list[list[dict[str, Any]]] = []
    with tempfile.TemporaryDirectory(prefix="homebot-bench-eval-") as scratch:
        folder = Path(scratch)
        suite = write_suite(folder / "suite", plan_split(episodes, [episodes], SEED_BASE, ("bench",)), hidden=False)
        jobs = full_budget_jobs(suite["bench"], config)
        for backend in ("pool", "ray") if with_ray else ("pool",):
            for count in workers:
                results = folder / f"{backend}-{count}.jsonl"
                started = time.monotonic()
                if backend == "ray":
                    with ray_backend.cluster(ray_backend.LOCAL, math.ceil(count * config.ray.cpus_per_episode)):
                        start_s = time.monotonic() - started
                        run_jobs(jobs, results, count, config, ray=ray_backend.LOCAL)
                else:
                    start_s = 0.0
                    run_jobs(jobs, results, count, config)
                seconds = time.monotonic() - started
                done = read_results(results)
                rows.append({"backend": backend, "workers": count, "episodes": len(done),
                             "failed": sum(r["status"] == "failed" for r in done),
                             "seconds": round(seconds, 2), "cluster_start_s": round(start_s, 2),
                             "episodes_per_minute": round(60.0 * len(done) / seconds, 2),
                             "without_start": round(60.0 * len(done) / (seconds - start_s), 2)})
                records.append(comparable(done))
                rows[-1]["differs_from_first"] = differences(records[0], records[-1])
                progress(f"  {backend} × {count}: {len(done)} episodes in {seconds:.1f} s")
    return {"episodes": episodes, "budget": budget, "cpus_per_episode": config.ray.cpus_per_episode,
            "runs": rows, "same_records": not any(row["differs_from_first"] for row in rows)}


def differences(first: list[dict[str, Any]], other: list[dict[str, Any]]) -> list[str]:
    """Where two runs' records of the same episodes differ: ``"ID VARIANT: field, field"`` per
    episode that does (or that only one run has).

    Args:
        first: one run's records (`comparable`).
        other: another run's.

    Returns:
        One line per episode that differs; none when they agree.
    """
    mine = {(r["id"], r["variant"]): r for r in first}
    theirs = {(r["id"], r["variant"]): r for r in other}
    lines = []
    for key in sorted(mine.keys() | theirs.keys()):
        a, b = mine.get(key), theirs.get(key)
        fields = ["(only one run has it)"] if a is None or b is None else [f for f in a if a[f] != b.get(f)]
        if fields:
            lines.append(f"{key[0]} {key[1]}: {', '.join(fields)}")
    return lines


def format_eval_table(report: dict[str, Any]) -> str:
    """The `bench_eval` report as a table: one row per backend and worker count.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    lines = [f"bench eval: {report['episodes']} episodes of {report['budget']} steps each; Ray tasks declare "
             f"{report['cpus_per_episode']:g} CPUs",
             f"{'backend':<8}{'workers':>8}{'episodes':>10}{'failed':>8}{'seconds':>10}{'cluster start s':>17}"
             f"{'episodes/min':>14}{'without start':>15}"]
    for row in report["runs"]:
        lines.append(f"{row['backend']:<8}{row['workers']:>8}{row['episodes']:>10}{row['failed']:>8}"
                     f"{row['seconds']:>10.1f}{row['cluster_start_s']:>17.1f}{row['episodes_per_minute']:>14.2f}"
                     f"{row['without_start']:>15.2f}")
    lines.append("every run gave the same records (timing aside)" if report["same_records"]
                 else "the runs' records differ (timing aside):")
    for row in report["runs"]:
        lines += [f"  {row['backend']} × {row['workers']} against the first run: {line}"
                  for line in row["differs_from_first"]]
    return "\n".join(lines)
