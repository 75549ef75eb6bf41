"""`homebot watch`: follow a running agent's tree snapshots from another process.

Like py-trees-tree-watcher, it renders the tree on every snapshot: each behaviour with its status,
its feedback message, the visited path in full and the rest dimmed, and the blackboard keys the
visited behaviours use.
"""

from __future__ import annotations

import json
import queue
import sys
import time
from typing import Any, TextIO

import zenoh

from worlds.bus.keys import ANY_AGENT_TREE, Keys

_GLYPHS = {"SUCCESS": ("✔", "32"), "FAILURE": ("✕", "31"), "RUNNING": ("*", "33"), "INVALID": ("-", "90")}


class SnapshotError(ValueError):
    """A snapshot that is not the JSON object a tree snapshot must be."""


def parse_snapshot(payload: bytes) -> dict[str, Any]:
    """Decode one snapshot; reject anything else with the reason (never evaluated, only parsed).

    Args:
        payload: the sample's bytes.

    Returns:
        The snapshot.

    Raises:
        SnapshotError: the payload is not a snapshot.
    """
    try:
        data = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SnapshotError(f"snapshot: not UTF-8 JSON ({error})") from None
    if not isinstance(data, dict) or not isinstance(data.get("behaviours"), list):
        raise SnapshotError("snapshot: expected an object with a 'behaviours' list")
    return data


def render(data: dict[str, Any], colour: bool) -> str:
    """The snapshot as indented text.

    Args:
        data: the snapshot.
        colour: whether to colour statuses with ANSI codes.

    Returns:
        The text.
    """
    def paint(text: str, code: str) -> str:
        return f"\x1b[{code}m{text}\x1b[0m" if colour else text

    behaviours = data["behaviours"]
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
        lines.append(paint("blackboard (visited behaviours' keys)", "1"))
        lines.extend(f"  {key}: {value}" for key, value in blackboard.items())
    return "\n".join(lines)


def watch(session: zenoh.Session, namespace: str | None, once: bool, as_json: bool, timeout_s: float,
          out: TextIO = sys.stdout, refresh_hz: float = 10.0) -> int:
    """Print snapshots as they come; with ``once``, the first one. Returns an exit code.

    The live tree is redrawn at most ``refresh_hz`` times a second, always with the newest
    snapshot (an agent ticks far faster than a terminal can usefully redraw). JSON output gets
    every snapshot.

    Args:
        session: the bus session.
        namespace: the agent's namespace (any agent when None).
        once: whether to stop after the first snapshot.
        as_json: whether to print JSON rather than the tree.
        timeout_s: how long to wait for a snapshot.
        out: where to print.
        refresh_hz: redraws a second at most.

    Returns:
        0, or 1 when no snapshot came in time.
    """
    key = Keys(namespace).agent_tree if namespace else ANY_AGENT_TREE
    inbox: queue.Queue[bytes] = queue.Queue(maxsize=256)

    def on_sample(sample: zenoh.Sample) -> None:
        try:
            inbox.put_nowait(sample.payload.to_bytes())
        except queue.Full:  # a slow terminal skips frames rather than falling behind
            pass

    subscriber = session.declare_subscriber(key, on_sample)
    colour = out.isatty() and not as_json
    try:
        while True:
            try:
                payload = inbox.get(timeout=timeout_s)
            except queue.Empty:
                sys.stderr.write(f"homebot watch: no tree snapshot on {key} within {timeout_s:.0f} s "
                                 "(is `homebot run` running, and is --connect its --listen endpoint?)\n")
                return 1
            if not as_json:
                payload = _newest(inbox, payload)
            try:
                data = parse_snapshot(payload)
            except SnapshotError as error:
                sys.stderr.write(f"homebot watch: skipped a bad snapshot: {error}\n")
                continue
            text = json.dumps(data, ensure_ascii=False) if as_json else render(data, colour)
            if colour:
                out.write("\x1b[H\x1b[2J")
            out.write(text + "\n")
            out.flush()
            if once:
                return 0
            if not as_json:
                time.sleep(1.0 / refresh_hz)
    except KeyboardInterrupt:
        return 0
    finally:
        subscriber.undeclare()


def _newest(inbox: queue.Queue[bytes], payload: bytes) -> bytes:
    """The last snapshot waiting in ``inbox`` (or ``payload`` if none), dropping older ones."""
    while True:
        try:
            payload = inbox.get_nowait()
        except queue.Empty:
            return payload
