"""Success, target seen and coverage against normalised time, as in Explore until Confident's Fig. 7.

Every episode runs to its full budget T and records each step's scores. Stopping after k steps
would answer argmax f̂ at the most relevant of those k steps, so one run gives the answer at every
k. At normalised time τ an episode has taken k = max(1, floor(τ·T)) steps; an episode that ended
earlier (nothing left to explore) keeps its last answer.

Beside success goes the share of episodes that have had the question's target in view by τ, from
the world's episode report (`worlds.evaluation`). The world numbers head frames from 0 and the tree
takes one per step, so after k steps frames 0..k-1 have been taken: the target has been seen when
its first frame's number is below k. A method that sees the target as early as another yet answers
worse has a VLM or stopping problem, not an exploration one. Coverage (the share of the home's free
floor seen) and the rooms entered after k steps come from the same report, frame k-1's figures:
they show whether a method covers the home or keeps going back to where it has been.
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
    """The answer an episode would give if it stopped after its first ``k`` steps.

    Args:
        step_scores: the episode's step records.
        k: the steps kept.

    Returns:
        The answer's letter, or None with no step.
    """
    steps = steps_from_records(step_scores[:k])
    return AnswerLog(steps).fallback().best() if steps else None


def steps_taken(result: dict[str, Any], taus: np.ndarray) -> np.ndarray:
    """How many steps an episode has taken at each normalised time: max(1, floor(τ·T)).

    Args:
        result: the episode's result (its ``budget`` T).
        taus: the normalised times τ.

    Returns:
        The steps, one per τ.
    """
    budget = max(1, int(result["budget"]))
    return np.maximum(1, np.floor(taus * budget + 1e-9).astype(int))


def success_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """1.0 where the episode's answer at each normalised time is right, else 0.0.

    Args:
        result: the episode's result.
        taus: the normalised times.

    Returns:
        One value per τ.
    """
    return np.array([answer_after(result["step_scores"], int(k)) == result["ground_truth"]
                     for k in steps_taken(result, taus)], dtype=float)


def target_seen_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """1.0 where the question's target had been in a head frame by each normalised time, else 0.0.

    Args:
        result: the episode's result, with the world's report.
        taus: the normalised times.

    Returns:
        One value per τ.
    """
    seen = result["evaluation"]["target_seen"]
    first = np.inf if seen is None else seen["step"]
    return (first < steps_taken(result, taus)).astype(float)


def coverage_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """The share of the home's free floor seen by each normalised time (0..1).

    Args:
        result: the episode's result, with the world's report.
        taus: the normalised times.

    Returns:
        One share per τ.
    """
    evaluation = result["evaluation"]
    seen = _by_frame(evaluation["floor_seen_by_frame"], steps_taken(result, taus))
    return seen / evaluation["free_floor_m2"] if evaluation["free_floor_m2"] > 0 else np.zeros(len(taus))


def rooms_entered_at(result: dict[str, Any], taus: np.ndarray = TAU_GRID) -> np.ndarray:
    """How many rooms the base has entered by each normalised time.

    Args:
        result: the episode's result, with the world's report.
        taus: the normalised times.

    Returns:
        One count per τ.
    """
    return _by_frame(result["evaluation"]["rooms_entered_by_frame"], steps_taken(result, taus))


def _by_frame(values: list[float], steps: np.ndarray) -> np.ndarray:
    """A per-head-frame figure after each number of steps; an episode that ended early keeps its last."""
    if not values:
        return np.zeros(len(steps))
    return np.asarray(values, dtype=float)[np.minimum(steps, len(values)) - 1]


def success_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Mean success per method at each τ, over that method's finished episodes.

    Args:
        results: the episodes' results.
        taus: the normalised times.

    Returns:
        The rates by method.
    """
    return _rates(results, success_at, lambda result: bool(result.get("step_scores")), taus)


def target_seen_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Share of each method's finished episodes with the target seen by each τ; episodes without a
    world's report (an older results file, a world that went away) are left out.

    Args:
        results: the episodes' results.
        taus: the normalised times.

    Returns:
        The rates by method.
    """
    return _rates(results, target_seen_at,
                  lambda result: bool(result.get("step_scores")) and result.get("evaluation") is not None, taus)


def coverage_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Mean share of the free floor seen per method at each τ, over episodes with a report.

    Args:
        results: the episodes' results.
        taus: the normalised times.

    Returns:
        The rates by method.
    """
    return _rates(results, coverage_at, _reported, taus)


def rooms_entered_curves(results: list[dict[str, Any]], taus: np.ndarray = TAU_GRID) -> Rates:
    """Mean number of rooms entered per method at each τ, over episodes with a report.

    Args:
        results: the episodes' results.
        taus: the normalised times.

    Returns:
        The means by method.
    """
    return _rates(results, rooms_entered_at, _reported, taus)


def _reported(result: dict[str, Any]) -> bool:
    evaluation = result.get("evaluation")
    return bool(result.get("step_scores")) and evaluation is not None and "floor_seen_by_frame" in evaluation


def _rates(results: list[dict[str, Any]], measure: Callable[[dict[str, Any], np.ndarray], np.ndarray],
           counted: Callable[[dict[str, Any]], bool], taus: np.ndarray) -> Rates:
    by_method: dict[str, list[np.ndarray]] = {}
    for result in results:
        if counted(result):
            by_method.setdefault(result["method"], []).append(measure(result, taus))
    return Rates({method: np.mean(rows, axis=0) for method, rows in sorted(by_method.items())},
                 {method: len(rows) for method, rows in sorted(by_method.items())})


@dataclass(frozen=True)
class Panel:
    """One measure's curves as the CSV and the figure show them: a column prefix, an axis label and
    a heading; ``percent``: the rates are shares, shown ×100."""

    rates: Rates
    column: str
    ylabel: str
    heading: str
    percent: bool = True


def explore_panels(results: list[dict[str, Any]], title: str, taus: np.ndarray = TAU_GRID) -> list[Panel]:
    """Success, target seen, floor seen and rooms entered, in that order.

    Args:
        results: the episodes' results.
        title: the success panel's title.
        taus: the normalised times.

    Returns:
        The panels.
    """
    return [
        Panel(success_curves(results, taus), "", "success rate [%]", title),
        Panel(target_seen_curves(results, taus), " target seen", "target seen so far [%]",
              "Has the question's target been in view?"),
        Panel(coverage_curves(results, taus), " floor seen", "free floor seen [%]", "Coverage of the home"),
        Panel(rooms_entered_curves(results, taus), " rooms entered", "rooms entered (mean)",
              "Rooms the base has entered", percent=False),
    ]


def write_curves_csv(path: Path, panels: list[Panel], taus: np.ndarray = TAU_GRID) -> None:
    """One row per τ: each panel's columns, one per method (success first, as `explore_panels` orders).

    Args:
        path: the CSV file.
        panels: the panels.
        taus: the normalised times.
    """
    columns = [(f"{m}{panel.column} (n={n})", panel.rates.by_method[m])
               for panel in panels for m, n in panel.rates.counts.items()]
    with open(path, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(["normalised_time", *(name for name, _ in columns)])
        for i, tau in enumerate(taus):
            writer.writerow([f"{tau:.2f}", *(f"{curve[i]:.4f}" for _, curve in columns)])


def plot_curves(path: Path, panels: list[Panel], taus: np.ndarray = TAU_GRID) -> None:
    """The panels side by side, two to a row, one colour per method throughout.

    Args:
        path: the image file.
        panels: the panels.
        taus: the normalised times.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = (len(panels) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(11.5, 4.2 * rows), dpi=120, sharex=True, squeeze=False)
    methods = sorted(set().union(*(panel.rates.counts for panel in panels)))
    colours = {method: f"C{i}" for i, method in enumerate(methods)}
    for ax, panel in zip(axes.ravel(), panels):
        scale = 100 if panel.percent else 1
        for method, curve in panel.rates.by_method.items():
            ax.plot(taus, scale * curve, marker="o", ms=3, lw=2, color=colours[method],
                    label=f"{method} (n={panel.rates.counts[method]})")
        ax.set_xlabel("normalised time step (steps / budget)")
        ax.set_ylabel(panel.ylabel)
        ax.set_xlim(0, 1)
        if panel.percent:
            ax.set_ylim(0, 100)
        else:
            ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.set_title(panel.heading, fontsize=10)
        ax.legend(loc="lower right", fontsize=8)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
