"""`homebot bench plan`: what one LFE planning step costs, against the number of frontiers.

The robot explores a few evaluation homes with LFE, and each planning step's three parts are timed
as it decides: the network's estimates, the known-space distances (one distance field for the robot
and each of the up to six frontiers planned over) and the Bellman recursion. The ground-truth
labelling the oracle uses is timed on the same maps, for comparison.

The paper's reference code re-plans every known-space path on every branch of the recursion; the
cost of doing that here is estimated as (branches of the full recursion) × (time of one distance
field), an upper bound since branches that run out of time end early, and shown as a ratio to the
step as computed here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agent.lfe.bellman import PLANNED_FRONTIERS
from agent.lfe.coverage import run_coverage
from agent.lfe.estimator import LearnedEstimator
from agent.lfe.methods import bellman_chooser, learned
from agent.lfe.properties import label_frontiers
from agent.lfe.task import CoverageConfig, Situation, TrueHome
from agent.timing import StageTimer

#: Frontier counts are reported in these bins (upper bounds, inclusive).
BINS = (1, 2, 3, 4, 6, 9, 14, 20, math.inf)


def branches(frontiers: int) -> int:
    """Q evaluations of the full recursion over ``frontiers`` (at most six): Σ_k n!/(n−k)!.

    Args:
        frontiers: the frontiers of the planning step.

    Returns:
        The count.
    """
    n = min(frontiers, PLANNED_FRONTIERS)
    return sum(math.perm(n, k) for k in range(1, n + 1))


def bench_plan(homes: Sequence[tuple[int, float]], model: Path | None = None, steps: int = 200,
               progress: Callable[[int, int, int], None] | None = None) -> dict[str, Any]:
    """Time every planning step of LFE exploring each (seed, area m²) home for ``steps`` steps.

    The parts are timed inside the chooser the episode runs (`bellman_chooser`'s timer), so what is
    measured is what was decided; only the oracle's labelling is extra work, done on the same map.

    Args:
        homes: the (seed, area m²) homes.
        model: the network file (the shipped one when None).
        steps: the episode's steps per home.
        progress: called with (home number, homes, plans so far), if given.

    Returns:
        The report: a row per frontier count, with medians in ms.
    """
    from worlds.home import generate_home

    estimator = LearnedEstimator.load(model)
    config = CoverageConfig(budget_steps=steps)
    samples: list[dict[str, float]] = []
    for number, (seed, area) in enumerate(homes, start=1):
        home = TrueHome.from_home(generate_home(seed, area_m2=area), config, seed)
        timer = StageTimer()
        oracle: list[tuple[int, float]] = []  # per planning step: frontiers offered, labelling ms

        def label(situation: Situation, _: int, home: TrueHome = home) -> None:
            with timer.measure("oracle"):
                label_frontiers(home.free, situation.observed, situation.frontiers, situation.spec.resolution)
            oracle.append((len(situation.frontiers), timer.samples["oracle"][-1]))

        run_coverage(home, bellman_chooser(learned(estimator), config.forward_m, timer), config, on_plan=label)
        parts = zip(timer.samples["properties"], timer.samples["distances"], timer.samples["recursion"], oracle)
        samples += [{"frontiers": frontiers, "network_s": network / 1000, "distances_s": distances / 1000,
                     "recursion_s": recursion / 1000, "oracle_s": labelling / 1000,
                     "field_s": distances / 1000 / (min(frontiers, PLANNED_FRONTIERS) + 1),
                     "branches": branches(frontiers)}
                    for network, distances, recursion, (frontiers, labelling) in parts]
        if progress:
            progress(number, len(homes), len(oracle))
    return {"homes": [{"seed": seed, "area_m2": area} for seed, area in homes], "steps": steps,
            "plans": len(samples), "rows": _binned(samples)}


def _binned(samples: list[dict[str, float]]) -> list[dict[str, Any]]:
    """Median figures per bin of frontier counts, in milliseconds."""
    rows, low = [], 1
    for high in BINS:
        mine = [s for s in samples if low <= s["frontiers"] <= high]
        low = int(high) + 1 if math.isfinite(high) else low
        if not mine:
            continue
        median = {key: float(np.median([s[key] for s in mine]))
                  for key in ("network_s", "distances_s", "recursion_s", "oracle_s", "field_s", "branches")}
        ours = median["network_s"] + median["distances_s"] + median["recursion_s"]
        per_branch = median["branches"] * median["field_s"] + median["network_s"] + median["recursion_s"]
        rows.append({"frontiers": _bin_name(mine), "plans": len(mine),
                     "network_ms": 1000 * median["network_s"], "distances_ms": 1000 * median["distances_s"],
                     "recursion_ms": 1000 * median["recursion_s"], "step_ms": 1000 * ours,
                     "oracle_ms": 1000 * median["oracle_s"], "per_branch_ms": 1000 * per_branch,
                     "per_branch_ratio": per_branch / ours if ours > 0 else math.nan})
    return rows


def _bin_name(samples: list[dict[str, float]]) -> str:
    counts = [int(s["frontiers"]) for s in samples]
    return f"{min(counts)}" if min(counts) == max(counts) else f"{min(counts)}-{max(counts)}"


def format_plan_table(report: dict[str, Any]) -> str:
    """The `bench_plan` report as a table: one row per frontier count, medians in ms.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    homes = ", ".join(f"{h['seed']} ({h['area_m2']:.0f} m²)" for h in report["homes"])
    lines = [f"bench plan: LFE exploring homes {homes} for {report['steps']} steps, {report['plans']} planning "
             "steps; medians in ms",
             f"{'frontiers':>10}{'plans':>7}{'network':>9}{'distances':>11}{'recursion':>11}{'step':>8}"
             f"{'oracle':>9}{'per-branch':>12}{'ratio':>7}"]
    for row in report["rows"]:
        lines.append(f"{row['frontiers']:>10}{row['plans']:>7}{row['network_ms']:>9.1f}{row['distances_ms']:>11.1f}"
                     f"{row['recursion_ms']:>11.2f}{row['step_ms']:>8.1f}{row['oracle_ms']:>9.1f}"
                     f"{row['per_branch_ms']:>12.0f}{row['per_branch_ratio']:>6.0f}×")
    lines.append("step = network + distances (computed once) + recursion; oracle = the ground-truth labelling "
                 "LFE-(R°, D°) plans with;")
    lines.append("per-branch = estimated cost of re-planning each path on every branch of the full recursion, as "
                 "the paper's reference code does")
    lines.append("(ratio to step; an upper bound, since branches that run out of time end early).")
    return "\n".join(lines)
