"""What the act branch did over an evaluation: how often the robot opened storage, looked inside and
shut it again, how often that answered the question, and why the rest failed.

Every episode's result keeps its ``acts`` (one record per attempt, `behaviours.look_inside`), and
`homebot eval explore` copies them into its results file. Run over that file::

    .venv/bin/homebot eval acts runs/eval-explore/explore-results.jsonl [--method semantic]

Failure reasons are grouped by the stage they happened at (open, close, stow) and a cause read off
the reason's wording (`CAUSES`); the reasons themselves are in the file.

`homebot eval explore` runs every episode to its full budget and answers argmax f̂ at the most
relevant step, where one irrelevant view that the VLM happens to rate highly outweighs the view
inside. The default stopping rule (conformal prediction) stops on the first view that leaves one
answer; exploration does not depend on the rule until it stops, so what it would have answered is
replayed over the recorded steps (`agent.eqa.stopping.replay`) and counted too.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from agent.app.config import load_config
from agent.eqa.answers import steps_from_records
from agent.app.runtime.calibrations import calibration_for
from agent.eqa.stopping import StoppingRule, make_rule, replay
from worlds.bus.questions import LETTERS

#: (pattern in a failure's reason, the cause it names), first match wins.
CAUSES: tuple[tuple[str, str], ...] = (
    (r"^stand: ", "no stand clear of the opening within reach"),
    (r"the base could not reach", "the base was blocked on its way"),
    (r"did not (open|close)", "the part was held back"),
    (r"closed on nothing|lost the", "the grasp missed the handle"),
    (r"stopped on contact|held it back", "the arm touched something"),
    (r"too low over the surface", "the handle is too low over a surface"),
    (r"IK: |unreachable", "out of the arm's reach"),
    (r"still running after", "timed out"),
)


def cause(reason: str) -> str:
    """The cause a failure's reason names (`CAUSES`), else "other".

    Args:
        reason: a failure's reason.

    Returns:
        The cause's name.
    """
    return next((name for pattern, name in CAUSES if re.search(pattern, reason)), "other")


@dataclass
class ActSummary:
    """Counts over episodes (``episodes``…) and over act records (``acts``…)."""

    episodes: int = 0
    correct: int = 0
    correct_stopping: int = 0  # answered right had the stopping rule given stopped it
    episodes_acting: int = 0  # tried to open something at least once
    episodes_looked: int = 0  # the VLM saw inside at least once
    correct_looked: int = 0
    inside_views: int = 0  # views inside scored by the VLM (their step is recorded; one per act, however many parts)
    inside_right: int = 0  # of which the VLM's best answer was the right one
    acts: int = 0
    opened: int = 0  # the skill counted the part open
    looked: int = 0  # frames taken inside went to the VLM
    closed: int = 0  # shut again, of those that stood open
    left_open: int = 0
    failures: Counter[tuple[str, str]] = field(default_factory=Counter)  # (stage, cause) -> acts

    def add(self, result: dict[str, Any], stopping: Callable[[], StoppingRule] | None = None) -> None:
        """Count one finished episode's acts, its answer, and with ``stopping`` the stopped answer.

        Args:
            result: the episode's result.
            stopping: makes a fresh stopping rule, if given.
        """
        acts = result.get("acts") or []
        right = result.get("answer") is not None and result.get("answer") == result.get("ground_truth")
        looked = any(act.get("looked") for act in acts)
        self.episodes += 1
        self.correct += right
        if stopping is not None and result.get("step_scores"):
            decision = replay(stopping(), steps_from_records(result["step_scores"]), max(1, int(result["budget"])))
            self.correct_stopping += decision.letter == result.get("ground_truth")
        self.episodes_acting += bool(acts)
        self.episodes_looked += looked
        self.correct_looked += right and looked
        scores = result.get("step_scores") or []
        # Every part of a piece opened in one act is shown to the VLM in one view: count it once.
        for step in sorted({act.get("step") for act in acts if isinstance(act.get("step"), int)}):
            if 0 < step <= len(scores):
                probs = scores[step - 1]["answer_probs"]
                self.inside_views += 1
                self.inside_right += max(probs, key=probs.get) == result.get("ground_truth")
        for act in acts:
            self.acts += 1
            self.opened += bool(act.get("opened"))
            self.looked += bool(act.get("looked"))
            self.closed += act.get("closed") is True
            self.left_open += act.get("closed") is False
            if act.get("stage"):
                self.failures[(act["stage"], cause(act.get("reason", "")))] += 1


def summarise(results: Iterable[dict[str, Any]], method: str | None = None,
              stopping: Callable[[], StoppingRule] | None = None) -> ActSummary:
    """The summary of every finished result (of ``method`` only, when given); with ``stopping`` (a
    fresh rule per call) also how many it would have answered right.

    Args:
        results: the episodes' results.
        method: the only method counted, if given.
        stopping: makes a fresh stopping rule, if given.

    Returns:
        The summary.
    """
    summary = ActSummary()
    for result in results:
        if result.get("status") != "failed" and (method is None or result.get("variant") == method):
            summary.add(result, stopping)
    return summary


def default_stopping() -> Callable[[], StoppingRule]:
    """Fresh copies of the default stopping rule: conformal prediction at the default ε with the
    calibration that ships for the default policy and VLM.

    Returns:
        A function making a fresh rule per call.
    """
    config = load_config()
    calibration, _ = calibration_for(config)
    q_hat = calibration.q_hat(config.stop.epsilon)
    return lambda: make_rule(config.stop, q_hat, LETTERS)


def format_summary(summary: ActSummary) -> str:
    """The summary as lines a person reads: answers, acts and their outcomes, failure causes.

    Args:
        summary: the summary.

    Returns:
        The text.
    """
    def share(part: int, whole: int) -> str:
        return f"{part}/{whole} ({100 * part / whole:.0f} %)" if whole else f"{part}/0"

    lines = [
        f"episodes answered right        {share(summary.correct, summary.episodes)} at the full budget, "
        f"{share(summary.correct_stopping, summary.episodes)} stopped by the stopping rule",
        f"episodes that tried to open    {share(summary.episodes_acting, summary.episodes)}",
        f"episodes that looked inside    {share(summary.episodes_looked, summary.episodes)}, "
        f"answered right {share(summary.correct_looked, summary.episodes_looked)}",
        f"acts: opened                   {share(summary.opened, summary.acts)}",
        f"acts: looked inside            {share(summary.looked, summary.acts)}",
        f"acts: closed again             {share(summary.closed, summary.closed + summary.left_open)}",
        f"views inside: VLM's best right {share(summary.inside_right, summary.inside_views)}",
        "failures (stage, cause):",
    ]
    lines += [f"  {count:>3}  {stage:<6} {name}" for (stage, name), count in summary.failures.most_common()]
    return "\n".join(lines)
