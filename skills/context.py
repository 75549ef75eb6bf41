"""What every skill is made with: the link to the world, and what the skills run over it share."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from worlds.bus.link import WorldLink

if TYPE_CHECKING:
    from skills.arm.planner import ArmPlanner


@dataclass
class SkillContext:
    """The world a skill acts in (``link``) and the arm's ``planner`` once some skill has built it
    from the world's description (building it takes a query and ~20 ms, so skills run in one
    context share it). Whoever runs skills owns the context; nothing about it is global."""

    link: WorldLink
    planner: ArmPlanner | None = None
