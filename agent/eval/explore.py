"""`homebot eval explore`: exploration methods compared over a suite, as in the paper's Q1 (Fig. 7).

Every scenario runs to its full budget under each method; the figure is the success rate against
normalised time, drawn from each episode's per-step scores (`agent.eval.curves`).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

from agent.config import Config
from agent.eval.curves import TAU_GRID, plot_curves, success_curves, write_curves_csv
from agent.eval.runner import Job, read_results, run_jobs
from worlds.suite import read_suite

METHODS = ("fbe", "semantic", "semantic-no-lsv", "semantic-no-gsv")


def explore_jobs(suite: Path, methods: list[str], limit: int | None) -> list[Job]:
    """Every (scenario, method) pair, methods interleaved so partial results stay comparable."""
    unknown = sorted(set(methods) - set(METHODS))
    if unknown:
        raise ValueError(f"--methods: unknown {', '.join(unknown)} (known: {', '.join(METHODS)})")
    entries = read_suite(suite)[:limit]
    return [
        Job(entry["id"], method, entry["seed"], entry["scenario"], (f"explore.method={method}",))
        for entry in entries
        for method in methods
    ]


def evaluate_explore(suite: Path, methods: list[str], out_dir: Path, workers: int, config: Config,
                     limit: int | None = None) -> dict[str, Any]:
    """Run what is missing, then write ``curves.csv`` and ``curves.png``; return the curves."""
    jobs = explore_jobs(suite, methods, limit)
    results_path = out_dir / "explore-results.jsonl"
    started = time.monotonic()

    def progress(done: int, total: int, result: dict[str, Any]) -> None:
        rate = (time.monotonic() - started) / done
        sys.stderr.write(f"\r  {done}/{total} episodes, last {result['variant']} {result['id']} "
                         f"({result['status']}), about {rate * (total - done) / 60:.1f} min left   ")
        sys.stderr.flush()

    ran = run_jobs(jobs, results_path, workers, config, progress)
    if ran:
        sys.stderr.write("\n")
    wanted = {job.key for job in jobs}
    results = [r for r in read_results(results_path) if (r["id"], r["variant"]) in wanted]
    for result in results:
        result["method"] = result["variant"]
    curves = success_curves(results)
    counts = {m: sum(r["method"] == m and bool(r["step_scores"]) for r in results) for m in curves}
    write_curves_csv(out_dir / "curves.csv", curves, counts)
    plot_curves(out_dir / "curves.png", curves, counts, f"Exploration methods on {suite.name}")
    failed = sum(r["status"] == "failed" for r in results)
    return {"curves": {m: c.tolist() for m, c in curves.items()}, "taus": TAU_GRID.tolist(),
            "counts": counts, "failed": failed, "results": str(results_path)}
