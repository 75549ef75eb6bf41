"""``homebot skills`` (what is installed, with each skill's ports) and ``homebot skill run`` (one skill,
made by its registered name, run against a simulated home)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from py_trees.common import Status

from agent.app.cli.options import (Commands, add_config_options, endpoint_option, load_settings, namespace_option,
                                   seconds_option, seed_option)
from skills.context import SkillContext
from skills.ports import PortError, PortedSkill
from skills.registry import SkillError, SkillRegistry
from skills.running import run_to_end


def add_command(commands: Commands) -> None:
    """Add ``skills`` and ``skill run`` to the command line.

    Args:
        commands: the `homebot` parser's commands.
    """
    listing = commands.add_parser("skills", help="list the installed skills (the homebot.skills entry points)")
    listing.add_argument("--json", action="store_true", help="print them as JSON")
    listing.set_defaults(handler=list_skills)
    skill = commands.add_parser("skill", help="run one installed skill against a simulated home")
    actions = skill.add_subparsers(dest="skill_command", required=True)
    run = actions.add_parser("run", help="make a skill by its registered name and tick it to its end")
    run.add_argument("name", help="the skill's registered name (see `homebot skills`)")
    run.add_argument("--port", action="append", default=[], metavar="KEY=VALUE",
                     help="bind an input port, e.g. --port look_point=0.4,0,0.8 (repeatable)")
    run.add_argument("--seed", type=seed_option, default=0, help="the home's seed (default 0)")
    run.add_argument("--tabletop", metavar="TASK", help="a tabletop scene of interactive exploration instead "
                     "of a home, e.g. drawer-only")
    run.add_argument("--connect", metavar="ENDPOINT", type=endpoint_option,
                     help="join a running world instead of starting one")
    run.add_argument("--namespace", type=namespace_option,
                     help="key prefix of the world to join (default homebot/default)")
    run.add_argument("--timeout", type=seconds_option, default=120.0, help="seconds the skill may run (default 120)")
    run.add_argument("--json", action="store_true", help="print the outcome as JSON")
    add_config_options(run)
    run.set_defaults(handler=run_skill_command)


def _rows(registry: SkillRegistry) -> list[dict[str, Any]]:
    rows = []
    for entry in registry.entries():
        problem = registry.problem(entry.name)
        row: dict[str, Any] = {"name": entry.name, "class": entry.target, "package": entry.distribution}
        if problem:
            row.update(summary=f"BROKEN: {problem}", ports=[])
        else:
            skill = registry.load(entry.name)
            doc = (skill.__doc__ or "").strip()
            row.update(summary=doc.splitlines()[0] if doc else "", ports=[port.describe() for port in skill.ports])
        rows.append(row)
    return rows


def list_skills(args: argparse.Namespace) -> int:
    """``homebot skills``: 0, or 1 when a skill is broken or declared twice.

    Args:
        args: the parsed command line (``--json``).

    Returns:
        The exit status.
    """
    rows = _rows(SkillRegistry())
    if args.json:
        print(json.dumps(rows, indent=2))
    elif not rows:
        print("no skills installed (entry-point group homebot.skills)")
    else:
        width = max(len(row["name"]) for row in rows)
        for row in rows:
            print(f"{row['name']:<{width}}  {row['summary']}")
            print(f"{'':<{width}}  {row['class']} ({row['package']})")
            for port in row["ports"]:
                print(f"{'':<{width}}    {port}")
    return 1 if any(row["summary"].startswith("BROKEN") for row in rows) else 0


def _bindings(pairs: list[str]) -> dict[str, str]:
    bindings = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip():
            raise PortError(f"--port {pair!r}: expected KEY=VALUE, e.g. --port look_point=0.4,0,0.8")
        bindings[key.strip()] = value.strip()
    return bindings


def run_skill_command(args: argparse.Namespace) -> int:
    """``homebot skill run``: 0 when the skill succeeds, 1 when it fails, 2 when it cannot be made.

    Args:
        args: the parsed command line: the skill, its bindings, the world.

    Returns:
        The exit status.
    """
    from agent.app.runtime.world_process import WorldProcess, WorldStartError
    from worlds.bus.keys import Keys, check_namespace
    from worlds.bus.link import WorldLink
    from worlds.bus.rpc import QueryFailed
    from worlds.bus.session import free_tcp_endpoint, open_session

    registry = SkillRegistry()
    try:
        bindings = _bindings(args.port)
        registry.load(args.name)
    except (SkillError, PortError) as error:
        print(f"homebot skill run: {error}", file=sys.stderr)
        return 2
    config = load_settings(args)
    namespace = check_namespace(args.namespace or ("homebot/default" if args.connect else
                                                   f"homebot/skill-{time.strftime('%H%M%S')}"))
    endpoint = args.connect or free_tcp_endpoint()
    session = open_session(connect=[endpoint], zenoh_config=config.bus.zenoh_config)
    link = WorldLink(session, Keys(namespace), config.bus.query_timeout_s)
    world = None
    try:
        skill = registry.create(args.name, SkillContext(link), bindings)
        if args.connect is None:
            folder = Path("runs") / f"skill-{args.name}-{time.strftime('%Y%m%d-%H%M%S')}"
            folder.mkdir(parents=True, exist_ok=True)
            world = WorldProcess(namespace, endpoint, config.camera, folder / "world.log",
                                 zenoh_config=config.bus.zenoh_config)
            world.wait_ready(link, config.bus.world_start_timeout_s)
        reset = {"seed": args.seed, **({"tabletop": args.tabletop} if args.tabletop else {})}
        link.call("reset", reset, timeout_s=config.bus.world_start_timeout_s)
        outcome = _tick_to_end(skill, args.timeout)
    except (SkillError, PortError) as error:
        print(f"homebot skill run: {error}", file=sys.stderr)
        return 2
    except (WorldStartError, QueryFailed) as error:
        print(f"homebot skill run: the world could not be reached: {error}", file=sys.stderr)
        return 1
    finally:
        link.close()
        if world is not None:
            world.stop()
        session.close()
    print(json.dumps(outcome, default=str) if args.json else
          f"{args.name}: {outcome['status']}: {outcome['feedback']}")
    return 0 if outcome["status"] == "SUCCESS" else 1


def _tick_to_end(skill: PortedSkill, timeout_s: float) -> dict[str, Any]:
    """Run the skill to its end (ticked when a world reply wakes it); its status, feedback and outputs."""
    result = run_to_end(skill, timeout_s)
    if skill.status not in (Status.SUCCESS, Status.FAILURE):  # raised, or still running at the deadline
        return {"status": "FAILURE", "feedback": result.message, "outputs": {}}
    outputs = {name: _plain(value) for name, value in skill.outputs.items()}
    return {"status": skill.status.name, "feedback": skill.feedback_message, "outputs": outputs}


def _plain(value: Any) -> Any:
    """An output as JSON can hold it (a dataclass's fields, arrays as lists)."""
    if hasattr(value, "__dataclass_fields__"):
        return {name: _plain(getattr(value, name)) for name in value.__dataclass_fields__}
    if hasattr(value, "tolist"):
        return value.tolist()
    return value
