"""Why the scenes of `homebot eval interactive` failed, counted by cause, so the next fix aims at the most.

A result row keeps its failed actions as the exploration log writes them
(``"<primitive> <label> (<node>) FAILED: <reason>"``). Each is put in one cause by its reason's
wording, which the skills spell in one place each (`skills.replies`, the planners' `SkillPlanError`
texts, the base's drive); a scene that failed with no action failed says the graph itself is wrong
(perception: something missed, merged or doubled), and a scene not put back as it was says so too.
Pure functions of the rows: they test on plain dicts.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

#: (cause, words any of which in a failed action's reason puts it there), tried in order: the
#: first that matches wins, so the narrower wording comes before the wider.
ACTION_CAUSES = (
    ("no room to lift it in storage", ("no room to lift it",)),
    ("beyond the arm's reach", ("beyond the arm's reach",)),
    ("light touch", ("too light for the world to report",)),
    ("held back against a contact", ("held back against",)),
    ("base unreachable", ("the base could not reach",)),
    ("contact stop", ("stopped on contact",)),
    ("IK no solution", ("IK:",)),
    ("no clear route in storage", ("none is taken unchecked",)),
    ("carry would meet what stands near", ("would carry it through",)),
    ("no idle space", ("idle spot", "no table or counter")),
    ("no handle points", ("has no handle the robot has seen", "points, need at least")),
    ("grasp closed on nothing", ("closed on nothing",)),
    ("part held back", ("did not open", "did not close")),
    ("grip lost", ("the gripper lost",)),
    ("wrong thing grasped", ("the gripper holds", "the fingers caught", "still holds")),
    ("blocked (symbolic)", ("is blocked by", "closed off by")),
    ("not undoable", ("was not picked away by this robot", "was not opened by this robot")),
    ("skill crashed or timed out", ("Error:", "still running after")),
)
#: A failed scene with no failed action: the explored graph differs from the truth by itself.
PERCEPTION = "graph wrong, no action failed (perception)"
#: A scene not left as it was found (an object not back within tolerance, a part left open).
NOT_RECOVERED = "state not recovered"
OTHER = "other"
_FAILED = " FAILED: "


def action_cause(failed_action: str) -> tuple[str, str]:
    """The primitive and the cause of one failed action, as a results row writes it.

    Args:
        failed_action: ``"<primitive> <label> (<node>) FAILED: <reason>"``.

    Returns:
        (primitive, cause); the cause is `OTHER` when no wording matches.
    """
    head, _, reason = failed_action.partition(_FAILED)
    primitive = head.split(" ", 1)[0] if head else "?"
    for cause, words in ACTION_CAUSES:
        if any(word in reason for word in words):
            return primitive, cause
    return primitive, OTHER


@dataclass
class CauseCount:
    """How often one cause appears: failed actions, failed scenes, and where (per task, per primitive)."""

    actions: int = 0
    scenes: int = 0
    tasks: Counter = field(default_factory=Counter)
    primitives: Counter = field(default_factory=Counter)

    def to_dict(self) -> dict[str, Any]:
        """The count as JSON, as the report keeps it.

        Returns:
            Actions, scenes, and tasks and primitives each most frequent first.
        """
        return {"actions": self.actions, "scenes": self.scenes, "tasks": dict(self.tasks.most_common()),
                "primitives": dict(self.primitives.most_common())}


def scene_causes(row: dict[str, Any]) -> dict[str, Counter]:
    """Cause -> failed actions per primitive, for one result row (scene-level causes count no action).

    Args:
        row: a result row: ``success``, ``state_recovered`` and, from the robot, ``failed_actions``.

    Returns:
        Every cause the scene shows; empty for a scene that succeeded and was put back.
    """
    causes: dict[str, Counter] = {}
    for failed in row.get("failed_actions") or ():
        primitive, cause = action_cause(str(failed))
        causes.setdefault(cause, Counter())[primitive] += 1
    if not float(row.get("success", 0.0)) and not causes:
        causes[PERCEPTION] = Counter()
    if float(row.get("state_recovered", 1.0)) < 1.0:
        causes[NOT_RECOVERED] = Counter()
    return causes


def cause_table(rows: Iterable[dict[str, Any]]) -> dict[str, CauseCount]:
    """Cause -> its count over the rows, the most scenes first (then the most actions).

    Every failed action counts, in whatever scene; ``scenes`` counts the scenes that failed (not a
    success, or not put back) and show the cause, so a failed action a scene recovered from does not
    count its scene.

    Args:
        rows: result rows (see `scene_causes`), each with its ``task``.

    Returns:
        The table.
    """
    table: dict[str, CauseCount] = {}
    for row in rows:
        failed = not float(row.get("success", 0.0)) or float(row.get("state_recovered", 1.0)) < 1.0
        for cause, primitives in scene_causes(row).items():
            count = table.setdefault(cause, CauseCount())
            count.actions += sum(primitives.values())
            count.primitives.update(primitives)
            if failed:
                count.scenes += 1
                count.tasks[row.get("task", "?")] += 1
    return dict(sorted(table.items(), key=lambda item: (-item[1].scenes, -item[1].actions, item[0])))


def format_cause_table(table: dict[str, dict[str, Any]]) -> str:
    """The cause table as Markdown: cause, failed actions, failed scenes, which tasks, which primitives.

    Args:
        table: cause -> `CauseCount.to_dict`, as a report keeps it.

    Returns:
        The table's lines; a single line when nothing failed.
    """
    if not table:
        return "no failures"
    lines = ["| cause | actions | failed scenes | tasks (scenes) | primitives (actions) |",
             "|-------|---------|---------------|----------------|----------------------|"]
    for cause, count in table.items():
        tasks = ", ".join(f"{task} {n}" for task, n in count["tasks"].items()) or "-"
        primitives = ", ".join(f"{name} {n}" for name, n in count["primitives"].items()) or "-"
        actions = str(count["actions"]) if cause not in (PERCEPTION, NOT_RECOVERED) else "-"
        lines.append(f"| {cause} | {actions} | {count['scenes']} | {tasks} | {primitives} |")
    return "\n".join(lines)
