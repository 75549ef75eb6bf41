"""`homebot watch`: follow a running agent's tree snapshots from another process.

Like py-trees-tree-watcher, it renders the tree as snapshots come: each behaviour with its status,
its feedback message, the visited path in full and the rest dimmed, the blackboard's readable
values and the writes since the last snapshot. Snapshots carry only what changed; the watcher
keeps the whole state (`agent.app.tree_state.TreeState`) and applies each one.
"""

from __future__ import annotations

import json
import queue
import sys
import time
from typing import Any, TextIO

import zenoh

from worlds.bus.keys import ANY_AGENT_TREE, Keys
from agent.app.tree_state import SnapshotError, TreeState, behaviour_rows, parse_snapshot

_GLYPHS = {"SUCCESS": ("✔", "32"), "FAILURE": ("✕", "31"), "RUNNING": ("*", "33"), "INVALID": ("-", "90")}


def render(data: dict[str, Any], colour: bool) -> str:
    """A whole state (`TreeState.apply`) as indented text.

    Args:
        data: the whole state.
        colour: whether to colour statuses with ANSI codes.

    Returns:
        The text.
    """
    def paint(text: str, code: str) -> str:
        return f"\x1b[{code}m{text}\x1b[0m" if colour else text

    behaviours = behaviour_rows(data)
    children: dict[str | None, list[dict[str, Any]]] = {}
    for behaviour in behaviours:
        children.setdefault(behaviour.get("parent"), []).append(behaviour)
    lines = [paint(f"run {data.get('run', '?')}  tick {data.get('tick', '?')}  "
                   f"({data.get('tick_ms', 0):.2f} ms)  tree {data.get('status', '?')}", "1")]

    def walk(parent: str | None, depth: int) -> None:
        for behaviour in children.get(parent, []):
            glyph, code = _GLYPHS.get(behaviour.get("status", "INVALID"), ("?", "0"))
            line = f"{'    ' * depth}{glyph} {behaviour['name']} [{behaviour.get('type', '')}]"
            if behaviour.get("message"):
                line += f" — {behaviour['message']}"
            lines.append(paint(line, code if behaviour.get("visited") else "90"))
            walk(behaviour["id"], depth + 1)

    walk(None, 0)
    blackboard = data.get("blackboard") or {}
    if blackboard:
        lines.append(paint("blackboard", "1"))
        lines.extend(f"  {key}: {value}" for key, value in blackboard.items())
    if data.get("activity"):
        lines.append(paint("written since the last snapshot", "1"))
        lines.extend(f"  tick {item['tick']}: {item['by']} {item['op']} {item['key']}" for item in data["activity"])
    return "\n".join(lines)


def watch(session: zenoh.Session, namespace: str | None, once: bool, as_json: bool, timeout_s: float,
          out: TextIO = sys.stdout, refresh_hz: float = 10.0) -> int:
    """Print the tree as snapshots come; with ``once``, the first whole state. Returns an exit code.

    Every snapshot is applied to the whole state (none may be skipped: each carries only what
    changed), and the live tree is redrawn at most ``refresh_hz`` times a second with the newest
    state (an agent ticks far faster than a terminal can usefully redraw). JSON output prints every
    whole state, one line each.

    Args:
        session: the bus session.
        namespace: the agent's namespace (any agent when None).
        once: whether to stop after the first whole state.
        as_json: whether to print JSON rather than the tree.
        timeout_s: how long to wait for a snapshot.
        out: where to print.
        refresh_hz: redraws a second at most.

    Returns:
        0, or 1 when no snapshot came in time.
    """
    key = Keys(namespace).agent_tree if namespace else ANY_AGENT_TREE
    inbox: queue.SimpleQueue[bytes] = queue.SimpleQueue()
    subscriber = session.declare_subscriber(key, lambda sample: inbox.put(sample.payload.to_bytes()))
    colour = out.isatty() and not as_json
    tree = TreeState()
    try:
        while True:
            try:
                payloads = [inbox.get(timeout=timeout_s)]
            except queue.Empty:
                sys.stderr.write(f"homebot watch: no tree snapshot on {key} within {timeout_s:.0f} s "
                                 "(is `homebot run` running, and is --connect its --listen endpoint?)\n")
                return 1
            while not inbox.empty():
                payloads.append(inbox.get())
            states = [state for state in map(lambda payload: _apply(tree, payload), payloads) if state is not None]
            if not states:
                continue
            texts = [json.dumps(state, ensure_ascii=False) for state in states] if as_json else [
                render(states[-1], colour)]
            if colour:
                out.write("\x1b[H\x1b[2J")
            out.write("\n".join(texts[:1] if once else texts) + "\n")
            out.flush()
            if once:
                return 0
            if not as_json:
                time.sleep(1.0 / refresh_hz)
    except KeyboardInterrupt:
        return 0
    finally:
        subscriber.undeclare()


def _apply(tree: TreeState, payload: bytes) -> dict[str, Any] | None:
    """The whole state after the snapshot ``payload``; None for a bad one (said on stderr) or while no
    full snapshot has come."""
    try:
        return tree.apply(parse_snapshot(payload))
    except SnapshotError as error:
        sys.stderr.write(f"homebot watch: skipped a bad snapshot: {error}\n")
        return None
