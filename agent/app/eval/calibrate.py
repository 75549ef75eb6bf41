"""`homebot calibrate`: run the calibration scenarios to their full budget and write q̂'s scores.

The episodes run with the exploration policy and VLM of the given config, each to its full budget
(early stopping would bias the scores), in parallel workers that each own a world. Every finished
episode is appended to ``<out>.episodes.jsonl`` at once, so an interrupted calibration resumes
where it stopped; the calibration file itself is rewritten atomically from all finished episodes.

A resumed run must use the policy the first run used, or its scores would mix two distributions:
``<out>.episodes.json`` holds what the episodes were made with and a changed config is refused.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from agent.app.config import Config
from agent.eqa.calibration import Calibration, CalibrationEpisode, CalibrationError, suite_identity
from agent.app.runtime.calibrations import made_with, mismatches, write_calibration
from agent.app.eval.runner import Job, WorldAddress, results_for, run_jobs, stderr_progress
from agent.app.runtime.record import write_json_atomic
from worlds.suite import checked_entries

FULL_BUDGET = "stop.rule=budget"  # calibration and evaluation episodes never stop early


def full_budget_jobs(suite: Path, config: Config, limit: int | None = None) -> list[Job]:
    """One full-budget episode per suite entry under the config's exploration method.

    Args:
        suite: the question suite.
        config: the settings.
        limit: the most entries used (all when None).

    Returns:
        The jobs.

    Raises:
        worlds.suite.SuiteError: the suite holds no scenario, a bad line, a repeated id, or a
            scenario whose home does not match (`worlds.suite.checked_entries`).
    """
    method = config.explore.method
    return [Job(entry["id"], method, entry["seed"], entry["scenario"], (FULL_BUDGET,))
            for entry in checked_entries(suite, limit)]


def episodes_path(out: Path) -> Path:
    """Where a calibration file's episodes are kept: beside it, as ``<name>.episodes.jsonl``.

    Args:
        out: the calibration file.

    Returns:
        The episodes' path.
    """
    return out.with_name(out.stem + ".episodes.jsonl")


def run_full_budget(jobs: list[Job], results_path: Path, workers: int, config: Config,
                    worlds: list[WorldAddress] | None = None, recordings: Path | None = None,
                    ray: str | None = None) -> list[dict[str, Any]]:
    """Run what is missing from ``results_path`` (refusing to mix policies) and return every job's result.

    Args:
        jobs: the episodes.
        results_path: the results file (JSON lines), resumed.
        workers: episodes run at once.
        config: the settings.
        worlds: the worlds to run in (started here when None).
        recordings: where to keep each episode's run folder with its Rerun recording (None: none kept).
        ray: run each episode as a Ray task (`run_jobs`): `ray_backend.LOCAL` or a cluster's address;
            None: in worker processes here.

    Returns:
        The results, in job order.
    """
    _check_same_policy(results_path.with_suffix(".json"), config)
    run_jobs(jobs, results_path, workers, config, stderr_progress(time.monotonic()), worlds, recordings, ray)
    return results_for(jobs, results_path)


def calibrate(suite: Path, out: Path, workers: int, config: Config, limit: int | None = None,
              worlds: list[WorldAddress] | None = None, ray: str | None = None) -> Calibration:
    """Run the calibration episodes still missing, then write the calibration file ``out``.

    Args:
        suite: the question suite.
        out: the calibration file.
        workers: episodes run at once.
        config: the settings.
        limit: the most entries used (all when None).
        worlds: the worlds to run in (started here when None).
        ray: run each episode as a Ray task (`run_jobs`): `ray_backend.LOCAL` or a cluster's address;
            None: in worker processes here.

    Returns:
        The calibration written.
    """
    jobs = full_budget_jobs(suite, config, limit)
    results = run_full_budget(jobs, episodes_path(out), workers, config, worlds, ray=ray)
    episodes = [CalibrationEpisode(r["id"], r["seed"], r["ground_truth"], r["step_scores"])
                for r in results if r["status"] != "failed" and r["step_scores"]]
    failed = [r["id"] for r in results if r["status"] == "failed" or not r["step_scores"]]
    if not episodes:
        raise CalibrationError(f"no calibration episode finished (failed: {len(failed)}); see {episodes_path(out)}")
    calibration = Calibration(made_with(config), suite_identity(suite, len(jobs)), episodes, failed)
    write_calibration(out, calibration)
    return calibration


def _check_same_policy(meta_path: Path, config: Config) -> None:
    """First run: record the policy. Resumed run: refuse a different one."""
    if not meta_path.exists():
        meta_path.parent.mkdir(parents=True, exist_ok=True)
        write_json_atomic(meta_path, {"made_with": made_with(config)})
        return
    differences = mismatches(json.loads(meta_path.read_text(encoding="utf-8"))["made_with"], config)
    if differences:
        raise CalibrationError(
            f"{meta_path.with_suffix('.jsonl')} holds episodes of another policy or VLM:\n  "
            + "\n  ".join(differences)
            + "\nUse the same settings to resume, or another --out to start afresh."
        )
