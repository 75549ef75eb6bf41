"""The skill registry: skills are found through the ``homebot.skills`` entry-point group.

A skill is one behaviour class plus one line in its package's metadata, so a package of new skills
installs beside homebot without touching it::

    [project.entry-points."homebot.skills"]
    wipe_table = "my_skills.wipe:WipeTable"

`installed_skills` lists every entry without importing them; `load_skill` imports one and checks
it is a py_trees behaviour. A broken entry (a missing module, a typo) is reported with its reason
rather than hiding the other skills.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points

import py_trees

GROUP = "homebot.skills"


class SkillError(LookupError):
    """A skill that is not installed or cannot be loaded; the text names it and says why."""


@dataclass(frozen=True)
class SkillEntry:
    """One installed skill: its name, where its class lives, and the distribution that declares it."""

    name: str
    target: str  # "module:Class"
    distribution: str

    def load(self) -> type[py_trees.behaviour.Behaviour]:
        module, _, attribute = self.target.partition(":")
        try:
            skill = EntryPoint(self.name, self.target, GROUP).load()
        except (ImportError, AttributeError) as error:
            raise SkillError(f"skill {self.name!r} ({self.target}): cannot be loaded: {error}") from None
        if not (isinstance(skill, type) and issubclass(skill, py_trees.behaviour.Behaviour)):
            raise SkillError(f"skill {self.name!r} ({self.target}): {module}.{attribute} is not a py_trees behaviour class")
        return skill

    def summary(self) -> str:
        """The first line of the class docstring, or why the class cannot be loaded."""
        try:
            doc = self.load().__doc__ or ""
        except SkillError as error:
            return f"BROKEN: {error}"
        return doc.strip().splitlines()[0] if doc.strip() else ""


def installed_skills() -> list[SkillEntry]:
    """Every skill declared by an installed distribution, sorted by name."""
    found = []
    for entry in entry_points(group=GROUP):
        distribution = entry.dist.name if entry.dist is not None else "?"
        found.append(SkillEntry(entry.name, entry.value, distribution))
    return sorted(found, key=lambda e: e.name)


def load_skill(name: str) -> type[py_trees.behaviour.Behaviour]:
    """The behaviour class of the skill called ``name``."""
    entries = {entry.name: entry for entry in installed_skills()}
    if name not in entries:
        known = ", ".join(entries) or "none"
        raise SkillError(f"no skill called {name!r} is installed (installed: {known})")
    return entries[name].load()
