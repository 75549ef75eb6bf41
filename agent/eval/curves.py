"""Success rate against normalised time, as in Explore until Confident's Fig. 7.

Every episode runs to its full budget T and records each step's scores. Stopping after k steps
would answer argmax f̂ at the most relevant of those k steps, so one run gives the answer at every
k. At normalised time τ an episode has taken k = max(1, floor(τ·T)) steps; an episode that ended
earlier (nothing left to explore) keeps its last answer.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from agent.eqa.answers import AnswerLog, steps_from_records

TAU_GRID = np.round(np.arange(0.05, 1.0001, 0.05), 2)


def answer_after(step_scores: list[dict[str, Any]], k: int) -> str | None:
    """The answer an episode would give if it stopped after its first ``k`` steps."""
    steps = steps_from_records(step_scores[:k])
    return AnswerLog(steps).fallback().best() if steps else None


def success_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """1.0 where the episode's answer at each normalised time is right, else 0.0."""
    budget = max(1, int(result["budget"]))
    ks = np.maximum(1, np.floor(taus * budget + 1e-9).astype(int))
    return np.array([answer_after(result["step_scores"], int(k)) == result["ground_truth"] for k in ks], dtype=float)


def success_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> dict[str, np.ndarray]:
    """Method -> mean success at each τ, over that method's finished episodes."""
    by_method: dict[str, list[np.ndarray]] = {}
    for result in results:
        if result.get("step_scores"):
            by_method.setdefault(result["method"], []).append(success_at(result, taus))
    return {method: np.mean(rows, axis=0) for method, rows in sorted(by_method.items())}


def write_curves_csv(path: Path, curves: dict[str, np.ndarray], counts: dict[str, int],
                     taus: np.ndarray = TAU_GRID) -> None:
    with open(path, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(["normalised_time", *(f"{m} (n={counts[m]})" for m in curves)])
        for i, tau in enumerate(taus):
            writer.writerow([f"{tau:.2f}", *(f"{curves[m][i]:.4f}" for m in curves)])


def plot_curves(path: Path, curves: dict[str, np.ndarray], counts: dict[str, int], title: str,
                taus: np.ndarray = TAU_GRID) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=120)
    for method, curve in curves.items():
        ax.plot(taus, 100 * curve, marker="o", ms=3, lw=2, label=f"{method} (n={counts[method]})")
    ax.set_xlabel("normalised time step (steps / budget)")
    ax.set_ylabel("success rate [%]")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
