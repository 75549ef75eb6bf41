"""The control protocol on the bus: the agent answers ``<ns>/agent/control/<verb>`` queries.

A request is a UTF-8 JSON object (an empty payload is ``{}``); the reply is UTF-8 JSON, ``{"ok":
true, ...state}`` with the state of `EpisodeControl.state`, or ``{"ok": false, "error": "<field>:
<problem>"}``. Requests are parsed, never evaluated, and answered one at a time by a thread of
their own, never by Zenoh's threads: ``pause`` and ``step`` reply once the tree has stopped (or
after a few seconds, if the tick in progress takes longer), and the tick in progress may be
waiting for a reply on the same session. The verbs and their fields are in docs/bus.md.
"""

from __future__ import annotations

import json
import logging
import queue
import threading
from typing import Any

import zenoh

from worlds.bus.keys import Keys
from agent.app.runtime.control import ControlRefused, EpisodeControl

log = logging.getLogger(__name__)

#: Each verb and the fields its request must have (and may have: no others).
VERBS: dict[str, tuple[str, ...]] = {
    "state": (), "pause": (), "continue": (), "step": (),
    "breakpoint": ("behaviour", "on"), "inject": ("behaviour", "fault"),
}
#: How long ``pause`` and ``step`` wait for the tree to stop before replying.
SETTLE_S = 5.0
MAX_REQUEST_BYTES = 64 * 1024


def parse_request(verb: str, payload: bytes | None) -> dict[str, Any]:
    """Decode and check one control request.

    Args:
        verb: the last chunk of the request's key.
        payload: the request's bytes (None or empty: ``{}``).

    Returns:
        The request's fields.

    Raises:
        ControlRefused: an unknown verb, a payload that is not a JSON object, an unknown, missing
            or mistyped field; the text names it.
    """
    if verb not in VERBS:
        raise ControlRefused(f"verb: {verb!r} is not one of {', '.join(VERBS)}")
    if payload and len(payload) > MAX_REQUEST_BYTES:
        raise ControlRefused(f"{verb}: the request has {len(payload)} bytes, more than {MAX_REQUEST_BYTES}")
    try:
        request = json.loads(payload.decode("utf-8")) if payload else {}
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise ControlRefused(f"{verb}: the request is not UTF-8 JSON ({error})") from None
    if not isinstance(request, dict):
        raise ControlRefused(f"{verb}: the request must be a JSON object, got {type(request).__name__}")
    fields = VERBS[verb]
    for key in request:
        if key not in fields:
            raise ControlRefused(f"{verb}.{key}: unknown field; {verb} takes {', '.join(fields) or 'no fields'}")
    for key in fields:
        if key not in request:
            raise ControlRefused(f"{verb}.{key}: missing")
    if verb == "breakpoint" and not isinstance(request["on"], bool):
        raise ControlRefused(f"breakpoint.on: expected true or false, got {request['on']!r}")
    return request


def answer(control: EpisodeControl, verb: str, payload: bytes | None, settle_s: float = SETTLE_S) -> dict[str, Any]:
    """Carry out one control request and make its reply.

    Args:
        control: the episode's control.
        verb: the request's verb.
        payload: the request's bytes.
        settle_s: how long ``pause`` and ``step`` wait for the tree to stop.

    Returns:
        ``{"ok": true, ...state}``, or ``{"ok": false, "error": "<field>: <problem>"}``.
    """
    try:
        request = parse_request(verb, payload)
        if verb == "pause":
            control.pause(settle_s)
        elif verb == "continue":
            control.resume()
        elif verb == "step":
            control.step(settle_s)
        elif verb == "breakpoint":
            control.set_breakpoint(request["behaviour"], request["on"])
        elif verb == "inject":
            control.inject(request["behaviour"], request["fault"])
    except ControlRefused as error:
        log.info("refused a control request: %s", error)
        return {"ok": False, "error": str(error)}
    return {"ok": True, **control.state()}


class ControlServer:
    """Answers the control queries of one episode under ``<ns>/agent/control/*`` until closed.

    Args:
        session: the agent's bus session.
        keys: the episode's keys.
        control: the episode's control.
        settle_s: how long ``pause`` and ``step`` wait for the tree to stop.
    """

    def __init__(self, session: zenoh.Session, keys: Keys, control: EpisodeControl,
                 settle_s: float = SETTLE_S) -> None:
        self._control = control
        self._keys = keys
        self._settle_s = settle_s
        self._inbox: queue.Queue[zenoh.Query | None] = queue.Queue()
        self._queryable = session.declare_queryable(keys.agent_control("*"), self._inbox.put)
        self._thread = threading.Thread(target=self._serve, name="episode-control", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop answering (the episode is over) and wait for the serving thread."""
        self._queryable.undeclare()
        self._inbox.put(None)
        self._thread.join()

    def _serve(self) -> None:
        while (query := self._inbox.get()) is not None:
            verb = str(query.key_expr).rpartition("/")[2]
            try:
                payload = query.payload.to_bytes() if query.payload is not None else None
                reply = answer(self._control, verb, payload, self._settle_s)
            except Exception as error:  # a bug must not stop the answering; the client is told
                log.exception("control request %s failed", verb)
                reply = {"ok": False, "error": f"internal error: {type(error).__name__}: {error}"}
            # a query on a wildcard (``**/agent/control/state``) learns which agent replied from the key
            key = self._keys.agent_control(verb) if verb in VERBS else query.key_expr
            try:
                query.reply(key, json.dumps(reply, ensure_ascii=False))
            except zenoh.ZError as error:
                log.warning("could not reply to a control request: %s", error)
            finally:
                query.drop()
