"""Asking a running agent to pause, step, stop at a behaviour or fail one (the control protocol).

One request, one reply (docs/bus.md, "Controlling an episode"). Without a namespace the client
first asks which agents answer and goes on only when exactly one does, so a request never reaches
an agent nobody named.
"""

from __future__ import annotations

import json
from typing import Any

import zenoh

from worlds.bus.keys import ANY_AGENT_CONTROL_STATE, Keys, control_namespace


class ControlFailed(RuntimeError):
    """No usable reply: nobody answered, several agents did, or the reply was not the protocol's."""


def find_agent(session: zenoh.Session, timeout_s: float) -> str:
    """The namespace of the one agent that answers control requests.

    Args:
        session: a session connected to the agent.
        timeout_s: how long to wait for answers.

    Returns:
        The namespace.

    Raises:
        ControlFailed: no agent answered, or several did (naming them).
    """
    try:
        namespaces = sorted({control_namespace(str(reply.ok.key_expr))
                             for reply in session.get(ANY_AGENT_CONTROL_STATE, timeout=timeout_s) if reply.ok})
    except ValueError as error:  # a reply on a key that is not an agent's control key
        raise ControlFailed(f"a reply to {ANY_AGENT_CONTROL_STATE}: {error}") from None
    if not namespaces:
        raise ControlFailed(f"no agent answered on {ANY_AGENT_CONTROL_STATE} within {timeout_s:g} s "
                            "(is `homebot run` running, and is --connect its --listen endpoint?)")
    if len(namespaces) > 1:
        raise ControlFailed(f"several agents answer ({', '.join(namespaces)}); name one with --namespace")
    return namespaces[0]


def send(session: zenoh.Session, namespace: str | None, verb: str, request: dict[str, Any] | None = None,
         timeout_s: float = 10.0) -> dict[str, Any]:
    """Send one control request and return the agent's reply, refusals included.

    Args:
        session: a session connected to the agent.
        namespace: the agent's namespace (None: the one agent that answers).
        verb: ``state``, ``pause``, ``continue``, ``step``, ``breakpoint`` or ``inject``.
        request: the request's fields.
        timeout_s: how long to wait for the reply.

    Returns:
        The reply: ``{"ok": true, ...state}`` or ``{"ok": false, "error": ...}``.

    Raises:
        ControlFailed: no agent (or several) answered, or the reply was not a JSON object with ``ok``.
    """
    key = Keys(namespace or find_agent(session, timeout_s)).agent_control(verb)
    payload = json.dumps(request or {})
    for reply in session.get(key, payload=payload, timeout=timeout_s):
        if not reply.ok:
            raise ControlFailed(f"{key}: {reply.err.payload.to_string()}")
        try:
            data = json.loads(reply.ok.payload.to_bytes().decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise ControlFailed(f"{key}: the reply is not UTF-8 JSON ({error})") from None
        if not isinstance(data, dict) or not isinstance(data.get("ok"), bool):
            raise ControlFailed(f"{key}: the reply is not a JSON object with 'ok'")
        return data
    raise ControlFailed(f"no agent answered on {key} within {timeout_s:g} s")


def describe(state: dict[str, Any]) -> str:
    """A control reply's state as a few lines of text.

    Args:
        state: the reply.

    Returns:
        The text.
    """
    if state.get("paused"):
        where = f"before {state['paused_before']}" if state.get("paused_before") else "between ticks"
        lines = [f"paused {where}, {state.get('tick')} ticks done"]
    else:
        lines = [f"running, {state.get('tick')} ticks done"]
    if state.get("breakpoints"):
        lines.append("breakpoints: " + ", ".join(state["breakpoints"]))
    if state.get("faults"):
        lines.append("pending faults: " + ", ".join(f"{f['behaviour']}={f['fault']}" for f in state["faults"]))
    lines.extend(f"injected: {i['fault']} into {i['behaviour']} on tick {i['tick']}" for i in state.get("injected", []))
    return "\n".join(lines)
