"""What the explore branch chose from, kept on the blackboard for whoever watches the episode (the
recording draws it): the frontiers `SelectFrontier` weighed, and the lettered points
`QueryDirections` showed the VLM with the value it gave each. Nothing in the tree reads them back.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FrontierChoice:
    """One candidate frontier of a choice: its centre (``x``, ``y``, world m), the path length to
    it (``distance_m``), its share of the semantic weight w_p / Σw (None where the method weighs
    none: FBE, LFE), and whether it was the one chosen."""

    x: float
    y: float
    distance_m: float
    weight: float | None
    chosen: bool


@dataclass(frozen=True)
class DirectionPrompt:
    """One lettered point of the visual prompt: its world floor position (``x``, ``y``, ``z``),
    its ``letter``, and the VLM's local semantic value for it (its probability among the letters)."""

    x: float
    y: float
    z: float
    letter: str
    value: float
