"""The skill registry: skills are found through the ``homebot.skills`` entry-point group.

A skill is one behaviour class plus one line in its package's metadata, so a package of new skills
installs beside homebot without touching it::

    [project.entry-points."homebot.skills"]
    wipe_table = "my_skills.wipe:WipeTable"

The class is a `skills.ports.PortedSkill` (or an `skills.base.ArmSkill`, for a skill that plans arm
motions) that declares its ports. `SkillRegistry` lists every entry without importing it, loads one
by name and makes it with its ports bound, as BehaviorTree.CPP's factory makes a node by its
registered name: the scene-graph executor, ``homebot skill run`` and skills put into a tree by
settings all make their skills here. A broken entry (a missing module, a typo, a class that is no
skill) and a name two packages both declare are reported by name, with their reason, rather than
hiding the other skills or letting one silently win.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Mapping

from skills.context import SkillContext
from skills.ports import Port, PortedSkill

GROUP = "homebot.skills"


class SkillError(LookupError):
    """A skill that is not installed or cannot be loaded; the text names it and says why."""


@dataclass(frozen=True)
class SkillEntry:
    """One installed skill: its name, where its class lives, and the distribution that declares it."""

    name: str
    target: str  # "module:Class"
    distribution: str

    def load(self) -> type[PortedSkill]:
        """Import the skill's class and check it is a skill.

        Returns:
            The class.

        Raises:
            SkillError: it cannot be imported, or is not a `PortedSkill` with well-formed ports.
        """
        module, _, attribute = self.target.partition(":")
        where = f"skill {self.name!r} ({self.target}, from {self.distribution})"
        try:
            skill = EntryPoint(self.name, self.target, GROUP).load()
        except (ImportError, AttributeError) as error:
            raise SkillError(f"{where}: cannot be loaded: {error}") from None
        if not (isinstance(skill, type) and issubclass(skill, PortedSkill)):
            raise SkillError(f"{where}: {module}.{attribute} is not a skill: a skill is a class derived from "
                             f"skills.ports.PortedSkill that declares its ports")
        if not all(isinstance(port, Port) for port in skill.ports):
            raise SkillError(f"{where}: its ports must be made with skills.ports.input_port / output_port")
        return skill


def installed_skills() -> list[SkillEntry]:
    """Every skill declared by an installed distribution, sorted by name (a name declared twice
    appears twice).

    Returns:
        The entries.
    """
    found = []
    for entry in entry_points(group=GROUP):
        distribution = entry.dist.name if entry.dist is not None else "?"
        found.append(SkillEntry(entry.name, entry.value, distribution))
    return sorted(found, key=lambda e: (e.name, e.distribution))


class SkillRegistry:
    """The installed skills by name, each class loaded once."""

    def __init__(self, entries: list[SkillEntry] | None = None) -> None:
        """Args:
            entries: the skills to offer (default: every installed one).
        """
        self._entries: dict[str, list[SkillEntry]] = {}
        for entry in installed_skills() if entries is None else entries:
            self._entries.setdefault(entry.name, []).append(entry)
        self._classes: dict[str, type[PortedSkill]] = {}

    def names(self) -> list[str]:
        """Every registered name, sorted.

        Returns:
            The names.
        """
        return sorted(self._entries)

    def entries(self) -> list[SkillEntry]:
        """Every entry, sorted by name (duplicates included).

        Returns:
            The entries.
        """
        return [entry for name in self.names() for entry in self._entries[name]]

    def problem(self, name: str) -> str:
        """Why the skill ``name`` cannot be used ("" when it can).

        Args:
            name: the skill's registered name.

        Returns:
            The reason, or "".
        """
        try:
            self.load(name)
        except SkillError as error:
            return str(error)
        return ""

    def load(self, name: str) -> type[PortedSkill]:
        """The class of the skill registered as ``name``.

        Args:
            name: the skill's registered name.

        Returns:
            The skill's class (loaded once, then kept).

        Raises:
            SkillError: no such skill, two packages declare it, or it cannot be loaded.
        """
        if name in self._classes:
            return self._classes[name]
        found = self._entries.get(name)
        if not found:
            raise SkillError(f"no skill called {name!r} is installed (installed: {', '.join(self.names()) or 'none'})")
        if len(found) > 1:
            places = " and ".join(f"{entry.target} (from {entry.distribution})" for entry in found)
            raise SkillError(f"skill {name!r} is declared twice: {places}; uninstall or rename one")
        self._classes[name] = found[0].load()
        return self._classes[name]

    def create(self, name: str, context: SkillContext, bindings: Mapping[str, Any] | None = None,
               node_name: str | None = None) -> PortedSkill:
        """Make the skill registered as ``name`` with its ports bound.

        Args:
            name: the registered name.
            context: the world link and what skills share.
            bindings: port name -> value, text, or ``"{key}"`` (see `skills.ports`).
            node_name: its name in a tree (default: the class name).

        Returns:
            The skill, ready to tick.

        Raises:
            SkillError: see `load`.
            skills.ports.PortError: a port bound wrongly.
        """
        return self.load(name)(context, node_name, bindings)
