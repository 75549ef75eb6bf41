"""Progress lines for the terminal while an episode runs: one per finished step."""

from __future__ import annotations

from typing import Any, TextIO


class StepPrinter:
    """A snapshot sink that prints the question once, then each step's VLM and move summaries.

    Args:
        out: where to print.
    """

    def __init__(self, out: TextIO) -> None:
        self.out = out
        self._printed: dict[str, str] = {}

    def __call__(self, data: dict[str, Any]) -> None:
        for behaviour in data["behaviours"]:
            if behaviour["name"] not in ("QueryVLM", "UpdatePredictionSet", "QueryDirections", "Navigate",
                                         "Answer", "AnswerFallback", "MarkExplorationComplete"):
                continue
            if behaviour["status"] != "SUCCESS" or not behaviour["visited"]:
                continue
            message = behaviour["message"]
            if self._printed.get(behaviour["name"]) != message:
                self._printed[behaviour["name"]] = message
                self.out.write(f"  {behaviour['name']:<19} {message}\n")
                self.out.flush()
