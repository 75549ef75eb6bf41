"""A behaviour that sends one command to the world and stays RUNNING until the reply arrives."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Status

from worlds.bus.codec import Message
from worlds.bus.rpc import PendingReply, QueryFailed
from worlds.bus.link import WorldLink


class WorldCommand(py_trees.behaviour.Behaviour):
    """Base for leaves that talk to the world.

    The command is sent in `initialise`; `update` polls for the reply without blocking, so the tree
    keeps ticking (and publishing snapshots) while the world works. The reply calls the ``wake``
    the tree handed `setup`, if any, so the tree ticks again as soon as it is in. A timeout, an
    error reply or a world that has gone turns into FAILURE with the reason as the feedback message.

    Args:
        name: the node's name.
        link: the world link.
        verb: the command sent.
        timeout_s: how long the reply may take (the link's default when None).
    """

    def __init__(self, name: str, link: WorldLink, verb: str, timeout_s: float | None = None) -> None:
        super().__init__(name)
        self.link = link
        self.verb = verb
        self.timeout_s = timeout_s
        self._pending: PendingReply | None = None
        self._request_error: str | None = None
        self._wake: Callable[[], None] | None = None

    def request(self) -> dict[str, Any]:
        """The command's metadata; raise ValueError if it cannot be formed.

        Returns:
            The command's metadata (empty by default).

        Raises:
            ValueError: the command cannot be formed from the blackboard.
        """
        return {}

    def on_reply(self, message: Message) -> Status:
        """Use the reply; return the behaviour's status.

        Args:
            message: the world's reply to the command.

        Returns:
            The behaviour's status.
        """
        raise NotImplementedError

    def setup(self, **kwargs: Any) -> None:
        """Take the tree's ``wake``, if it hands one: the world's reply then wakes the tree.

        Args:
            **kwargs: py_trees' setup arguments; ``wake`` is called once a reply is in.
        """
        self._wake = kwargs.get("wake")

    def initialise(self) -> None:
        self._pending, self._request_error = None, None
        try:
            self._pending = self.link.request(self.verb, self.request(), self.timeout_s, on_reply=self._wake)
        except (ValueError, QueryFailed) as error:
            self._request_error = f"{self.verb}: {error}"

    def update(self) -> Status:
        if self._pending is None:
            self.feedback_message = self._request_error or f"{self.verb}: not sent"
            return Status.FAILURE
        try:
            message = self._pending.poll()
        except QueryFailed as error:
            self.feedback_message = str(error)
            return Status.FAILURE
        if message is None:
            self.feedback_message = f"waiting for {self.verb} ({self._pending.elapsed_s:.1f} s)"
            return Status.RUNNING
        return self.on_reply(message)

    def terminate(self, new_status: Status) -> None:
        self._pending = None
