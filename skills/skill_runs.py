"""A record of the skills a robot ran: each run's name, outcome and the arm's joints it ended with.

A `SkillRuns` is a `skills.robot_body.RobotBody` skill listener: whoever wants to see the arm move
(a recording) attaches one, and reads `runs` and `joint_names` afterwards or as they grow.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from skills.base import SkillResult


@dataclass
class SkillRuns:
    """Each skill run's name, whether it succeeded and the arm's joints it ended with, in order;
    ``joint_names``: the joints' names in the order of those positions (empty until known)."""

    runs: list[tuple[str, bool, np.ndarray | None]] = field(default_factory=list)
    joint_names: tuple[str, ...] = ()

    def __call__(self, name: str, result: SkillResult) -> None:
        """Keep one run.

        Args:
            name: the skill's registered name.
            result: how it went.
        """
        self.runs.append((name, result.ok, result.joints))

    def joint(self, index: int) -> str:
        """The name of the joint at ``index`` of a run's positions (``joint<index>`` when unknown).

        Args:
            index: the position's index.

        Returns:
            The joint's name.
        """
        return self.joint_names[index] if index < len(self.joint_names) else f"joint{index}"
