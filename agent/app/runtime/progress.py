"""Progress lines for the terminal while an episode runs: one per finished step."""

from __future__ import annotations

from typing import Any, TextIO

from agent.app.tree_state import TreeState, behaviour_rows

_SHOWN = ("QueryVLM", "UpdatePredictionSet", "QueryDirections", "Navigate", "Answer", "AnswerFallback",
          "MarkExplorationComplete")


class StepPrinter:
    """A snapshot sink that prints each step's VLM and move summaries as they finish.

    Args:
        out: where to print.
    """

    def __init__(self, out: TextIO) -> None:
        self.out = out
        self._state = TreeState()
        self._printed: dict[str, str] = {}

    def __call__(self, data: dict[str, Any]) -> None:
        state = self._state.apply(data)
        if state is None:
            return
        for behaviour in behaviour_rows(state):
            if behaviour["name"] not in _SHOWN or behaviour["status"] != "SUCCESS" or not behaviour["visited"]:
                continue
            message = behaviour["message"]
            if self._printed.get(behaviour["name"]) != message:
                self._printed[behaviour["name"]] = message
                self.out.write(f"  {behaviour['name']:<19} {message}\n")
                self.out.flush()
