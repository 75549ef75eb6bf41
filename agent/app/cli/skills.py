"""`homebot skills`: the installed skills, found by their entry points."""

from __future__ import annotations

import argparse
import json

from agent.app.cli.options import Commands


def add_command(commands: Commands) -> None:
    """Add ``skills`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    skills = commands.add_parser("skills", help="list the installed skills (the homebot.skills entry points)")
    skills.add_argument("--json", action="store_true", help="print them as JSON")
    skills.set_defaults(handler=_skills)


def _skills(args: argparse.Namespace) -> int:
    """1 when a skill cannot be loaded (its summary says BROKEN), else 0."""
    from skills.registry import installed_skills

    entries = installed_skills()
    rows = [{"name": e.name, "class": e.target, "package": e.distribution, "summary": e.summary()} for e in entries]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    if not rows:
        print("no skills installed (entry-point group homebot.skills)")
        return 0
    width = max(len(row["name"]) for row in rows)
    for row in rows:
        print(f"{row['name']:<{width}}  {row['summary']}")
        print(f"{'':<{width}}  {row['class']} ({row['package']})")
    broken = sum(row["summary"].startswith("BROKEN") for row in rows)
    return 1 if broken else 0
