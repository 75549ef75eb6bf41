"""`homebot watch`: the running agents, a running agent's behaviour tree live (`agent.app.watch`),
and one-shot control requests to it: pause, continue, step, breakpoints, injected faults
(`agent.app.control_client`)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from typing import Any

import zenoh

from worlds.bus.session import open_session
from agent.app.agents import AgentInfo, find_agents
from agent.app.cli.options import DEFAULT_AGENT_ENDPOINT, Commands, add_zenoh_config_option

_FAULTS = ("failure", "raise")


def add_command(commands: Commands) -> None:
    """Add ``watch`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    watch = commands.add_parser("watch", help="list the running agents; show one's behaviour tree live, or control it")
    watch.add_argument("--connect", default=DEFAULT_AGENT_ENDPOINT, metavar="ENDPOINT",
                       help=f"an agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT}, "
                            "through which every agent of this machine is reached)")
    watch.add_argument("--list", action="store_true", help="list the running agents: run id, namespace, endpoint")
    watch.add_argument("--run", metavar="RUN_ID", help="watch this run (its id as --list shows it)")
    watch.add_argument("--namespace", help="only this run's namespace (default: any run)")
    watch.add_argument("--once", action="store_true", help="print one snapshot and exit")
    watch.add_argument("--json", action="store_true", help="print snapshots (the list, or the control reply) as JSON")
    watch.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for a snapshot (default 30)")
    watch.add_argument("--gather", type=float, default=1.5,
                       help="seconds --list waits for agents to announce themselves (default 1.5)")
    add_zenoh_config_option(watch)
    control = watch.add_mutually_exclusive_group()
    control.add_argument("--state", dest="control", action="store_const", const=("state", {}),
                         help="print whether the agent is paused, its breakpoints and faults, and exit")
    control.add_argument("--pause", dest="control", action="store_const", const=("pause", {}),
                         help="pause the agent before its next tick")
    control.add_argument("--continue", dest="control", action="store_const", const=("continue", {}),
                         help="let a paused agent run freely")
    control.add_argument("--step", dest="control", action="store_const", const=("step", {}),
                         help="run a paused agent to the next tick boundary (one tick), then pause")
    control.add_argument("--break", dest="control", metavar="NAME", type=_breakpoint(True),
                         help="pause right before the behaviour NAME ticks, every time")
    control.add_argument("--unbreak", dest="control", metavar="NAME", type=_breakpoint(False),
                         help="clear the breakpoint on NAME")
    control.add_argument("--inject", dest="control", metavar="NAME=failure|raise", type=_fault,
                         help="make NAME's next tick fail without running, or raise InjectedFault")
    watch.set_defaults(handler=_watch)


def _breakpoint(on: bool) -> Callable[[str], tuple[str, dict[str, Any]]]:
    """The argparse type of ``--break`` (``on``) or ``--unbreak``: a ``breakpoint`` request."""
    def parse(name: str) -> tuple[str, dict[str, Any]]:
        if not name:
            raise argparse.ArgumentTypeError("expected a behaviour's name")
        return "breakpoint", {"behaviour": name, "on": on}
    return parse


def _fault(text: str) -> tuple[str, dict[str, Any]]:
    """``NAME=failure`` or ``NAME=raise`` as an ``inject`` request."""
    name, _, fault = text.rpartition("=")
    if not name or fault not in _FAULTS:
        raise argparse.ArgumentTypeError(f"expected NAME=failure or NAME=raise, got {text!r}")
    return "inject", {"behaviour": name, "fault": fault}


def _watch(args: argparse.Namespace) -> int:
    """Follow an agent's tree, list the agents, or send one control request; the exit code."""
    if args.run is not None and args.namespace is not None:
        print("homebot watch: --run and --namespace: give one (a run's id names its namespace)", file=sys.stderr)
        return 2
    endpoint, namespace = args.connect, args.namespace
    if args.list or args.run is not None:
        session = open_session(connect=[args.connect], zenoh_config=args.zenoh_config)
        try:
            found = find_agents(session, args.gather if args.list else args.timeout, args.run)
        finally:
            session.close()
        if args.list:
            return _list(found, args.json)
        if not found:
            print(f"homebot watch: --run {args.run}: no such agent announced itself through {args.connect} within "
                  f"{args.timeout:.0f} s (`homebot watch --list` shows the running ones)", file=sys.stderr)
            return 1
        endpoint, namespace = found[0].endpoint, found[0].namespace
    session = open_session(connect=[endpoint], zenoh_config=args.zenoh_config)
    try:
        if args.control is not None:
            return _control(session, namespace, args)
        from agent.app.watch import watch

        return watch(session, namespace, args.once, args.json, args.timeout)
    finally:
        session.close()


def _list(agents: list[AgentInfo], as_json: bool) -> int:
    """Print the agents as a table, or as a JSON list of {run_id, namespace, endpoint}."""
    if as_json:
        print(json.dumps([{"run_id": a.run_id, "namespace": a.namespace, "endpoint": a.endpoint} for a in agents]))
        return 0
    if not agents:
        print("no running agents", file=sys.stderr)
        return 0
    width = max(len(a.run_id) for a in agents)
    for agent in agents:
        print(f"{agent.run_id:<{width}}  {agent.namespace}  {agent.endpoint}")
    return 0


def _control(session: zenoh.Session, namespace: str | None, args: argparse.Namespace) -> int:
    """Send the one control request and print the reply's state; 1 when refused or unanswered."""
    from agent.app.control_client import ControlFailed, describe, send

    verb, request = args.control
    try:
        reply = send(session, namespace, verb, request, args.timeout)
    except ControlFailed as error:
        print(f"homebot watch: {error}", file=sys.stderr)
        return 1
    if not reply["ok"]:
        print(f"homebot watch: the agent refused: {reply.get('error')}", file=sys.stderr)
        return 1
    print(json.dumps(reply, ensure_ascii=False) if args.json else describe(reply))
    return 0
