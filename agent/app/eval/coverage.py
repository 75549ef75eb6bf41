"""`homebot eval coverage`: the coverage task of learning-augmented exploration, the paper's Table I.

Each method explores the same homes from the same start with a 360° sensor for 500 steps, and the
score is the share of the home's free floor it has observed (`agent.lfe.coverage`). Homes come in
three sizes by floor area; their seeds are far from the training data's (which start at 0), so no
home is evaluated that the network was trained on. One result row per (home, method) is appended
as it finishes, and a rerun resumes where the last one stopped. Rows of the learned methods carry
the digest of the network that made them, so a rerun with another model runs them again instead
of mixing two networks in one table.
"""

from __future__ import annotations

import functools
import hashlib
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from agent.acsg.metrics import mean_and_sem
from agent.app.eval.runner import append_results, read_results
from agent.app.progress import counted
from agent.lfe.methods import Method
from agent.app.runtime.pool import as_finished

if TYPE_CHECKING:
    from agent.lfe.estimator import LearnedEstimator

#: Floor area (m²) of each size of home: the generator's 60-300 m² in three bands.
SIZES: dict[str, tuple[float, float]] = {"small": (60.0, 100.0), "medium": (100.0, 180.0), "large": (180.0, 300.0)}
#: Homes are seeded from here on: training homes (`homebot lfe data`) take seeds 0, 1, 2, ...
SEED_BASE = 1_000_000
#: Coverage % of the paper's Table I (360° sensor, 500 steps): small, medium, large, overall.
PAPER = {Method.FBE_NEAR: (92.7, 74.8, 61.0, 76.8), Method.GREEDY: (95.8, 72.3, 56.7, 74.4),
         Method.LFE: (97.4, 75.1, 70.9, 80.7), Method.LFE_ORACLE: (95.2, 84.0, 79.5, 86.2)}
CURVE_EVERY = 10  # steps between the points of a stored coverage curve
RESULTS = "coverage-results.jsonl"


@dataclass(frozen=True)
class CoverageJob:
    """One episode of the evaluation: a home of a size, explored by a method."""

    size: str
    seed: int
    method: str
    steps: int = 500  # the step budget
    model: str | None = None  # digest of the network (`model_digest`); None for methods without one

    @property
    def key(self) -> tuple[str, int, str, int, str | None]:
        """What makes two result rows the same episode."""
        return self.size, self.seed, self.method, self.steps, self.model


LEARNED = (Method.LFE, Method.GREEDY)
"""The methods that read the network."""


def model_digest(model: Path | None) -> str:
    """The first 12 hex digits of the SHA-256 of the network file (the shipped one for None).

    Args:
        model: the network file, or None.

    Returns:
        The digest.
    """
    from agent.lfe.estimator import SHIPPED_MODEL

    return hashlib.sha256((SHIPPED_MODEL if model is None else model).read_bytes()).hexdigest()[:12]


def jobs(homes_per_size: int, methods: Iterable[str], steps: int = 500, model: str | None = None) -> list[CoverageJob]:
    """Every (home, method) pair, homes in size order, methods in the given order per home; the
    learned methods' jobs carry ``model``, the digest of the network they use.

    Args:
        homes_per_size: the homes per size band.
        methods: the exploration methods.
        steps: each episode's steps.
        model: the network's digest, for the learned methods.

    Returns:
        The jobs.
    """
    methods = list(methods)
    return [CoverageJob(size, SEED_BASE + 1000 * band + index, method, steps, model if method in LEARNED else None)
            for band, size in enumerate(SIZES) for index in range(homes_per_size) for method in methods]


def home_area(size: str, seed: int) -> float:
    """The floor area of the home of ``seed``, drawn within its size band.

    Args:
        size: the size band.
        seed: the home's seed.

    Returns:
        The area (m²).
    """
    low, high = SIZES[size]
    return float(np.random.default_rng(seed).uniform(low, high))


@functools.lru_cache(maxsize=None)
def load_estimator(model: Path | None) -> LearnedEstimator:
    """The network of ``model``, loaded once per process: on the first learned episode a worker runs.

    Args:
        model: the network file; None for the shipped one.

    Returns:
        The estimator, the same object on every later call with the same ``model``.
    """
    from agent.lfe.estimator import LearnedEstimator

    return LearnedEstimator.load(model)


def run_job(job: CoverageJob, model: Path | None) -> dict[str, Any]:
    """One episode of the evaluation, run in a worker process or here.

    Args:
        job: the home and the method.
        model: the network file of the learned methods; None for the shipped one.

    Returns:
        The episode's result row: the final coverage, the curve every `CURVE_EVERY` steps and the
        planning statistics.
    """
    import torch

    from agent.lfe.coverage import run_coverage
    from agent.lfe.methods import make_chooser
    from agent.lfe.task import CoverageConfig, TrueHome
    from worlds.home import generate_home

    torch.set_num_threads(1)  # one episode per core: workers, not threads, use the machine
    started = time.monotonic()
    config = CoverageConfig(budget_steps=job.steps)
    home = TrueHome.from_home(generate_home(job.seed, area_m2=home_area(job.size, job.seed)), config, job.seed)
    estimator = load_estimator(model) if job.method in LEARNED else None
    result = run_coverage(home, make_chooser(job.method, home, estimator, config), config)
    return {"size": job.size, "seed": job.seed, "method": job.method, "budget": job.steps, "model": job.model,
            "area_m2": round(home.area_m2, 2),
            "coverage": round(100.0 * float(result.coverage[-1]), 3),
            "curve": [round(100.0 * float(v), 3) for v in result.coverage[::CURVE_EVERY]],
            "steps_used": result.steps_used, "exhausted": result.exhausted,
            "plans": len(result.plan_seconds),
            "plan_ms": round(1000.0 * float(np.mean(result.plan_seconds)), 3) if result.plan_seconds else 0.0,
            "seconds": round(time.monotonic() - started, 3)}


def evaluate_coverage(out_dir: Path, homes_per_size: int, methods: Iterable[str], workers: int = 1,
                      model: Path | None = None, steps: int = 500,
                      progress: Callable[[int, int, dict[str, Any]], None] | None = None,
                      ray: str | None = None) -> dict[str, Any]:
    """Run the episodes not yet in ``<out_dir>/coverage-results.jsonl``; return the table.

    Args:
        out_dir: where results, table and plot go.
        homes_per_size: the homes per size band.
        methods: the exploration methods.
        workers: episodes run at once.
        model: the network file (the shipped one when None).
        steps: each episode's steps.
        progress: called with (done, total, row) after each episode, if given.
        ray: run each episode as a Ray task of one CPU (`agent.app.runtime.pool.as_finished`):
            `ray_backend.LOCAL` or a cluster's address; None: in worker processes here.

    Returns:
        The table (`coverage_table`), the rows, the results file and the episode count.

    Raises:
        ValueError: an unknown method, none, or a count, step budget or model file that is not usable.
    """
    methods = list(methods)
    unknown = sorted(set(methods) - set(Method))
    if unknown or not methods:
        raise ValueError(f"--methods: unknown {', '.join(unknown) or '(none given)'} "
                         f"(known: {', '.join(Method)})")
    if homes_per_size < 1:
        raise ValueError(f"--homes: {homes_per_size} must be at least 1")
    if workers < 1:
        raise ValueError(f"--workers: {workers} must be at least 1")
    if steps < 1:
        raise ValueError(f"--steps: {steps} must be at least 1")
    if model is not None and not model.is_file():
        raise ValueError(f"--model: {model} is not a file")
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / RESULTS
    done = {_key(r) for r in read_results(path)}
    wanted = jobs(homes_per_size, methods, steps, model_digest(model))
    todo = [job for job in wanted if job.key not in done]
    model = model.resolve() if model is not None else None  # a Ray task may run in another folder
    append_results(path, as_finished(run_job, [(job, model) for job in todo], workers, ray), len(todo), progress)
    keys = {job.key for job in wanted}
    rows = [r for r in read_results(path) if _key(r) in keys]
    return {"table": coverage_table(rows, methods), "rows": rows, "results": str(path), "n": len(rows)}


def _key(row: dict[str, Any]) -> tuple[str, int, str, int, str | None]:
    return row["size"], row["seed"], row["method"], row["budget"], row.get("model")


def coverage_table(rows: list[dict[str, Any]], methods: list[str]) -> dict[str, dict[str, tuple[float, float]]]:
    """Method -> size (and "overall", over every home) -> (mean coverage %, standard error).

    Args:
        rows: the episodes' results.
        methods: the methods, in the table's order.

    Returns:
        The table.
    """
    table: dict[str, dict[str, tuple[float, float]]] = {}
    for method in methods:
        mine = [r for r in rows if r["method"] == method]
        if not mine:
            continue
        table[method] = {size: mean_and_sem(r["coverage"] for r in mine if r["size"] == size)
                         for size in SIZES if any(r["size"] == size for r in mine)}
        table[method]["overall"] = mean_and_sem(r["coverage"] for r in mine)
    return table


def format_table(table: dict[str, dict[str, tuple[float, float]]]) -> str:
    """Our coverage beside the paper's, as a Markdown table a person can paste into a note.

    Args:
        table: the `coverage_table`.

    Returns:
        The Markdown.
    """
    columns = [*SIZES, "overall"]
    lines = ["| method | " + " | ".join(columns) + " | paper (" + " / ".join(columns) + ") |",
             "|---" * (len(columns) + 2) + "|"]
    for method, row in table.items():
        cells = [f"{row[c][0]:.1f} ± {row[c][1]:.1f}" if c in row else "–" for c in columns]
        paper = " / ".join(f"{v:.1f}" for v in PAPER[Method(method)])
        lines.append(f"| {method} | " + " | ".join(cells) + f" | {paper} |")
    return "\n".join(lines)


def plot_curves(rows: list[dict[str, Any]], methods: list[str], path: Path) -> Path:
    """Mean coverage against steps, one panel per size, one line per method.

    Args:
        rows: the episodes' results.
        methods: the methods.
        path: the image file.

    Returns:
        The path written.
    """
    from matplotlib.figure import Figure

    figure = Figure(figsize=(4.2 * len(SIZES), 3.6), layout="constrained")
    axes = figure.subplots(1, len(SIZES), sharey=True)
    for ax, size in zip(axes, SIZES):
        for method in methods:
            curves = [r["curve"] for r in rows if r["size"] == size and r["method"] == method]
            if not curves:
                continue
            mean = np.mean(np.asarray(curves, dtype=float), axis=0)
            ax.plot(np.arange(len(mean)) * CURVE_EVERY, mean, label=f"{method} ({mean[-1]:.1f} %)")
        homes = len({r["seed"] for r in rows if r["size"] == size})
        low, high = SIZES[size]
        ax.set_title(f"{size} homes, {low:g}-{high:g} m² (n={homes})")
        ax.set_xlabel("steps")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    axes[0].set_ylabel("coverage (% of free floor seen)")
    figure.savefig(path, dpi=120)
    return path


def episode_progress() -> Callable[[int, int, dict[str, Any]], None]:
    """A progress line on stderr (`agent.app.progress`): the episodes done and the last one's coverage.

    Returns:
        A ``progress`` callback for `evaluate_coverage`.
    """
    return counted("episodes", lambda row: f"{row['size']} home {row['seed']} {row['method']}: "
                   f"{row['coverage']:.1f} % in {row['seconds']:.0f} s")
