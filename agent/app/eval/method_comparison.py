"""`homebot eval explore`: exploration methods compared over a suite, as in the paper's Q1 (Fig. 7).

Every scenario runs to its full budget under each method; the figure is the success rate against
normalised time, drawn from each episode's per-step scores, beside the share of episodes that have
had the question's target in view by then, from the world's episode reports (`agent.app.eval.curves`).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from agent.app.config import Config
from agent.app.eval.curves import TAU_GRID, Rates, explore_panels, plot_curves, write_curves_csv
from agent.app.eval.runner import Job, WorldAddress, results_for, run_jobs, stderr_progress
from worlds.suite import checked_entries

METHODS = ("fbe", "semantic", "semantic-no-lsv", "semantic-no-gsv")


def explore_jobs(suite: Path, methods: list[str], limit: int | None) -> list[Job]:
    """Every (scenario, method) pair, methods interleaved so partial results stay comparable.

    Args:
        suite: the question suite.
        methods: the exploration methods.
        limit: the most entries used (all when None).

    Returns:
        The jobs.

    Raises:
        ValueError: an unknown method.
        worlds.suite.SuiteError: the suite holds no scenario, a bad line, a repeated id, or a
            scenario whose home does not match (`worlds.suite.checked_entries`).
    """
    unknown = sorted(set(methods) - set(METHODS))
    if unknown:
        raise ValueError(f"--methods: unknown {', '.join(unknown)} (known: {', '.join(METHODS)})")
    entries = checked_entries(suite, limit)
    return [
        Job(entry["id"], method, entry["seed"], entry["scenario"], (f"explore.method={method}", "stop.rule=budget"))
        for entry in entries
        for method in methods
    ]


def evaluate_explore(suite: Path, methods: list[str], out_dir: Path, workers: int, config: Config,
                     limit: int | None = None, worlds: list[WorldAddress] | None = None,
                     recordings: Path | None = None, ray: str | None = None) -> dict[str, Any]:
    """Run what is missing, then write ``curves.csv`` and ``curves.png``; return the curves.

    Args:
        suite: the question suite.
        methods: the exploration methods.
        out_dir: where the results and curves go.
        workers: episodes run at once.
        config: the settings.
        limit: the most entries used (all when None).
        worlds: the worlds to run in (started here when None).
        recordings: where to keep each episode's run folder with its Rerun recording (None: none kept).
        ray: run each episode as a Ray task (`run_jobs`): `ray_backend.LOCAL` or a cluster's address;
            None: in worker processes here.

    Returns:
        Every panel's curves by method, the τ grid, the episodes counted, the failures, the results file.
    """
    jobs = explore_jobs(suite, methods, limit)
    results_path = out_dir / "explore-results.jsonl"
    run_jobs(jobs, results_path, workers, config, stderr_progress(time.monotonic()), worlds, recordings, ray)
    results = results_for(jobs, results_path)
    for result in results:
        result["method"] = result["variant"]
    panels = explore_panels(results, f"Exploration methods on {suite.name}")
    write_curves_csv(out_dir / "curves.csv", panels)
    plot_curves(out_dir / "curves.png", panels)
    success, seen, floor, rooms = (panel.rates for panel in panels)
    failed = sum(r["status"] == "failed" for r in results)
    return {"curves": _lists(success), "taus": TAU_GRID.tolist(), "counts": success.counts,
            "target_seen": _lists(seen), "target_seen_counts": seen.counts,
            "floor_seen": _lists(floor), "rooms_entered": _lists(rooms), "reported_counts": floor.counts,
            "failed": failed, "results": str(results_path)}


def _lists(rates: Rates) -> dict[str, list[float]]:
    return {method: curve.tolist() for method, curve in rates.by_method.items()}
