"""The stopping-rule figure: success against normalised steps (Fig. 9), and coverage against 1 − ε."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from agent.app.eval.stop import SweepPoint

STYLE = {"cp": ("tab:blue", "o", "CP (ours), ε swept"),
         "relevance": ("tab:orange", "s", "Relevance, threshold swept"),
         "entropy": ("tab:green", "^", "Entropy, threshold swept")}


def plot_stop(path: Path, points: list[SweepPoint], coverage: list[dict[str, Any]], title: str) -> None:
    """Draw the stopping rules' success against steps beside the conformal set's coverage against 1 − ε.

    Args:
        path: the image file.
        points: the sweep's points.
        coverage: the coverage table's rows.
        title: the figure's title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (curves, cover) = plt.subplots(1, 2, figsize=(11.5, 4.6), dpi=120,
                                        gridspec_kw={"width_ratios": [1.5, 1]})
    for rule, (colour, marker, label) in STYLE.items():
        mine = sorted((p for p in points if p.rule == rule), key=lambda p: p.normalised_steps)
        curves.plot([p.normalised_steps for p in mine], [100 * p.success for p in mine], color=colour,
                    marker=marker, ms=4, lw=1.6, label=label)
    for point in points:
        if point.rule == "cp" and round(point.parameter, 2) in (0.05, 0.25, 0.45, 0.65):
            curves.annotate(f"ε={point.parameter:g}", (point.normalised_steps, 100 * point.success),
                            textcoords="offset points", xytext=(4, -11), fontsize=7, color="tab:blue")
    budget = next(p for p in points if p.rule == "budget")
    curves.plot([budget.normalised_steps], [100 * budget.success], "k*", ms=11,
                label="full budget (argmax f̂ at max Rel)")
    curves.set_xlabel("normalised steps taken (steps / budget)")
    curves.set_ylabel("success rate [%]")
    curves.set_xlim(0, 1.02)
    curves.grid(alpha=0.3)
    curves.legend(loc="lower right", fontsize=8)
    curves.set_title(title, fontsize=9)

    promised = [row["promised"] for row in coverage]
    achieved = [row["coverage"] for row in coverage]
    errors = [2 * row["standard_error"] for row in coverage]
    cover.plot([0, 1], [0, 1], color="grey", lw=1, ls="--", label="promised: 1 − ε")
    cover.errorbar(promised, achieved, yerr=errors, color="tab:blue", marker="o", ms=4, lw=1.4, capsize=2,
                   label="empirical coverage (±2 s.e.)")
    cover.plot(promised, [row["singletons"] for row in coverage], color="tab:purple", marker=".", lw=1,
               label="set holds one answer at the end")
    cover.set_xlabel("promised coverage 1 − ε")
    cover.set_ylabel("share of test episodes")
    cover.set_xlim(0.2, 1.0)
    cover.set_ylim(0, 1.02)
    cover.grid(alpha=0.3)
    cover.legend(loc="upper left", fontsize=8)
    cover.set_title("Does the conformal set keep its promise?", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
