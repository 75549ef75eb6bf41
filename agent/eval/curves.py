"""Success rate and target-seen rate against normalised time, as in Explore until Confident's Fig. 7.

Every episode runs to its full budget T and records each step's scores. Stopping after k steps
would answer argmax f̂ at the most relevant of those k steps, so one run gives the answer at every
k. At normalised time τ an episode has taken k = max(1, floor(τ·T)) steps; an episode that ended
earlier (nothing left to explore) keeps its last answer.

Beside success goes the share of episodes that have had the question's target in view by τ, from
the world's episode report (`worlds.evaluation`). The world numbers head frames from 0 and the tree
takes one per step, so after k steps frames 0..k-1 have been taken: the target has been seen when
its first frame's number is below k. A method that sees the target as early as another yet answers
worse has a VLM or stopping problem, not an exploration one.
"""

from __future__ import annotations

import csv
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agent.eqa.answers import AnswerLog, steps_from_records

TAU_GRID = np.round(np.arange(0.05, 1.0001, 0.05), 2)


@dataclass(frozen=True)
class Rates:
    """One measure's mean over each method's episodes at every τ, and how many episodes that is."""

    by_method: dict[str, np.ndarray]
    counts: dict[str, int]


def answer_after(step_scores: list[dict[str, Any]], k: int) -> str | None:
    """The answer an episode would give if it stopped after its first ``k`` steps."""
    steps = steps_from_records(step_scores[:k])
    return AnswerLog(steps).fallback().best() if steps else None


def steps_taken(result: dict[str, Any], taus: np.ndarray) -> np.ndarray:
    """How many steps an episode has taken at each normalised time: max(1, floor(τ·T))."""
    budget = max(1, int(result["budget"]))
    return np.maximum(1, np.floor(taus * budget + 1e-9).astype(int))


def success_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """1.0 where the episode's answer at each normalised time is right, else 0.0."""
    return np.array([answer_after(result["step_scores"], int(k)) == result["ground_truth"]
                     for k in steps_taken(result, taus)], dtype=float)


def target_seen_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """1.0 where the question's target had been in a head frame by each normalised time, else 0.0."""
    seen = result["evaluation"]["target_seen"]
    first = np.inf if seen is None else seen["step"]
    return (first < steps_taken(result, taus)).astype(float)


def success_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Mean success per method at each τ, over that method's finished episodes."""
    return _rates(results, success_at, lambda result: bool(result.get("step_scores")), taus)


def target_seen_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Share of each method's finished episodes with the target seen by each τ; episodes without a
    world's report (an older results file, a world that went away) are left out."""
    return _rates(results, target_seen_at,
                  lambda result: bool(result.get("step_scores")) and result.get("evaluation") is not None, taus)


def _rates(results: list[dict[str, Any]], measure: Callable[[dict[str, Any], np.ndarray], np.ndarray],
           counted: Callable[[dict[str, Any]], bool], taus: np.ndarray) -> Rates:
    by_method: dict[str, list[np.ndarray]] = {}
    for result in results:
        if counted(result):
            by_method.setdefault(result["method"], []).append(measure(result, taus))
    return Rates({method: np.mean(rows, axis=0) for method, rows in sorted(by_method.items())},
                 {method: len(rows) for method, rows in sorted(by_method.items())})


def write_curves_csv(path: Path, success: Rates, seen: Rates, taus: np.ndarray = TAU_GRID) -> None:
    """One row per τ: each method's success rate, then each method's target-seen rate."""
    columns = [(f"{m} (n={n})", success.by_method[m]) for m, n in success.counts.items()]
    columns += [(f"{m} target seen (n={n})", seen.by_method[m]) for m, n in seen.counts.items()]
    with open(path, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(["normalised_time", *(name for name, _ in columns)])
        for i, tau in enumerate(taus):
            writer.writerow([f"{tau:.2f}", *(f"{curve[i]:.4f}" for _, curve in columns)])


def plot_curves(path: Path, success: Rates, seen: Rates, title: str, taus: np.ndarray = TAU_GRID) -> None:
    """Success (left) and target seen (right) against normalised time, one colour per method in both."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.4), dpi=120, sharex=True)
    methods = sorted(set(success.counts) | set(seen.counts))
    colours = {method: f"C{i}" for i, method in enumerate(methods)}
    panels = ((axes[0], success, "success rate [%]", title),
              (axes[1], seen, "target seen so far [%]", "Has the question's target been in view?"))
    for ax, rates, ylabel, heading in panels:
        for method, curve in rates.by_method.items():
            ax.plot(taus, 100 * curve, marker="o", ms=3, lw=2, color=colours[method],
                    label=f"{method} (n={rates.counts[method]})")
        ax.set_xlabel("normalised time step (steps / budget)")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 100)
        ax.grid(alpha=0.3)
        ax.set_title(heading, fontsize=10)
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
