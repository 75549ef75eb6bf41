"""Skills put into the EQA tree by settings (``[[tree.skills]]``): made before the world starts, so a
misspelt skill or port stops the run at once, then inserted into the built tree."""

from __future__ import annotations

import py_trees

from agent.app.config import TreeSettings
from behaviours.insert import insert_after
from skills.context import SkillContext
from skills.ports import PortedSkill, PortError
from skills.registry import SkillError, SkillRegistry
from worlds.bus.link import WorldLink


class PlugError(ValueError):
    """A skill the settings put into the tree that cannot be made or placed; the text names the
    setting (``tree.skills[0]``) and the problem."""


def make_plugged_skills(settings: TreeSettings, link: WorldLink, registry: SkillRegistry | None = None
                        ) -> list[tuple[str, PortedSkill]]:
    """Each skill of ``settings.skills``, made with its ports bound, with the node it follows.

    Args:
        settings: the tree settings.
        link: the world the skills act in.
        registry: where skills are found (default: the installed ones).

    Returns:
        (anchor node name, skill) pairs, in the settings' order.

    Raises:
        PlugError: an unknown or broken skill, a port bound wrongly, no ``after``.
    """
    if not settings.skills:
        return []
    registry = registry or SkillRegistry()
    context = SkillContext(link)
    made = []
    for index, plug in enumerate(settings.skills):
        where = f"tree.skills[{index}]"
        if not plug.skill or not plug.after:
            raise PlugError(f"config: {where}: needs both skill (a registered name) and after (a node name)")
        try:
            made.append((plug.after, registry.create(plug.skill, context, plug.ports, plug.name or None)))
        except (SkillError, PortError) as error:
            raise PlugError(f"config: {where}: {error}") from None
    return made


def plug_into(root: py_trees.behaviour.Behaviour, plugged: list[tuple[str, PortedSkill]]) -> None:
    """Insert each made skill after its anchor node.

    Args:
        root: the tree.
        plugged: each skill with the name of the node it goes after.

    Raises:
        PlugError: an anchor the tree does not have, naming the nodes it has.
    """
    for index, (anchor, skill) in enumerate(plugged):
        try:
            insert_after(root, anchor, skill)
        except ValueError as error:
            raise PlugError(f"config: tree.skills[{index}].after: {error}") from None
