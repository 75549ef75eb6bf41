"""Where the inspector's states come from (a run folder's snapshot log, or the bus live), and the
control requests it forwards to a live agent's ``<ns>/agent/control/<verb>`` queryables."""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import zenoh

from worlds.bus.keys import ANY_AGENT_EVENTS, ANY_AGENT_TREE, Keys
from agent.app.inspector.history import History
from agent.app.tree_state import SnapshotError, parse_snapshot, read_log

log = logging.getLogger(__name__)

#: The control protocol's verbs (docs/bus.md).
VERBS = ("state", "pause", "continue", "step", "breakpoint", "inject")


class ControlError(ValueError):
    """A control request refused before it is sent; the text names the field."""


def load_run(run_dir: Path, history: History) -> None:
    """Fill ``history`` with a recorded run's snapshots.

    Args:
        run_dir: the run folder (with snapshots.jsonl).
        history: where the states go.

    Raises:
        FileNotFoundError: the folder has no snapshot log.
        SnapshotError: a line of the log is not a snapshot.
    """
    path = run_dir / "snapshots.jsonl"
    if not path.is_file():
        raise FileNotFoundError(f"RUN_DIR: no snapshots.jsonl in {run_dir}")
    for snapshot in read_log(path.read_text(encoding="utf-8")):
        history.add(snapshot)


class LiveAgent:
    """A live agent on the bus: its snapshots fill ``history``; control requests go to it.

    With no namespace it follows the first agent whose snapshots arrive (any namespace) and
    controls that one.

    Args:
        session: the bus session.
        namespace: the agent's namespace, or None for the first one heard.
        history: where the states go.
        timeout_s: how long a control request waits for the agent's reply.
    """

    def __init__(self, session: zenoh.Session, namespace: str | None, history: History,
                 timeout_s: float = 5.0) -> None:
        self.session = session
        self.namespace = namespace
        self.history = history
        self.timeout_s = timeout_s
        self.outcome: dict[str, Any] = {}  # how the episode ended, once it has: status, reason, injected
        key = Keys(namespace).agent_tree if namespace else ANY_AGENT_TREE
        self._subscriber = session.declare_subscriber(key, self._on_sample)
        events = Keys(namespace).agent_events if namespace else ANY_AGENT_EVENTS
        self._events = session.declare_subscriber(events, self._on_event)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        namespace = str(sample.key_expr).removesuffix("/agent/tree")
        if self.namespace is None:
            self.namespace = namespace
        if namespace != self.namespace:
            return
        try:
            self.history.add(parse_snapshot(sample.payload.to_bytes()))
        except SnapshotError as error:
            log.warning("skipped a bad snapshot: %s", error)

    def _on_event(self, sample: zenoh.Sample) -> None:
        """Keep how the followed episode ended (its ``ended`` event), as result.json would say it."""
        if str(sample.key_expr).removesuffix("/agent/events") != self.namespace:
            return
        try:
            event = json.loads(sample.payload.to_bytes().decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError):
            log.warning("skipped an episode event that is not UTF-8 JSON")
            return
        if not isinstance(event, dict) or event.get("event") != "ended":
            return
        extra = event.get("extra") if isinstance(event.get("extra"), dict) else {}
        self.outcome = {"status": event.get("status"), "reason": event.get("reason"),
                        **({"injected": extra["injected"]} if isinstance(extra.get("injected"), list) else {})}

    def control(self, verb: str, body: bytes) -> dict[str, Any]:
        """Forward one control request to the agent and return its reply.

        Args:
            verb: the request's verb (one of `VERBS`).
            body: the request's UTF-8 JSON object (empty for ``{}``).

        Returns:
            The agent's reply: ``{"ok": true, ...state}`` or ``{"ok": false, "error": ...}``.

        Raises:
            ControlError: the verb or the body is not a control request.
        """
        request = _control_request(verb, body)
        if self.namespace is None:
            return {"ok": False, "error": "control: no agent heard yet (no snapshot has come)"}
        key = Keys(self.namespace).agent_control(verb)
        for reply in self.session.get(key, payload=json.dumps(request), timeout=self.timeout_s):
            if reply.ok is None:
                return {"ok": False, "error": f"control: the agent's error reply on {key}: "
                                              f"{reply.err.payload.to_bytes().decode('utf-8', 'replace')}"}
            return _reply(key, reply.ok.payload.to_bytes())
        return {"ok": False, "error": f"control: no agent answers on {key} within {self.timeout_s:g} s"}

    def close(self) -> None:
        """Stop following the agent."""
        self._subscriber.undeclare()
        self._events.undeclare()


def _control_request(verb: str, body: bytes) -> dict[str, Any]:
    """The request object, checked: a known verb and a JSON object."""
    if verb not in VERBS:
        raise ControlError(f"verb: {verb!r} is not one of {', '.join(VERBS)}")
    try:
        request = json.loads(body.decode("utf-8")) if body.strip() else {}
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ControlError(f"body: not UTF-8 JSON ({error})") from None
    if not isinstance(request, dict):
        raise ControlError("body: expected a JSON object")
    return request


def _reply(key: str, payload: bytes) -> dict[str, Any]:
    """The agent's reply decoded, or an error reply saying why it could not be."""
    try:
        answer = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        return {"ok": False, "error": f"control: the agent's reply on {key} is not UTF-8 JSON ({error})"}
    if not isinstance(answer, dict) or not isinstance(answer.get("ok"), bool):
        return {"ok": False, "error": f"control: the agent's reply on {key} has no 'ok'"}
    return answer
