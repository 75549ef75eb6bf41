"""The question format both sides speak: a reset's scenario carries a question with four choices,
answered by letter.

A scenario with fewer real choices pads them with `PAD_CHOICE`, which the VLM prompt tells the
model not to choose; `LETTERS` name the four in order (``answer`` is one of them). The world writes
questions in this format and the agent reads them, so it lives on the wire (docs/bus.md), not in
either side's vocabulary.
"""

from __future__ import annotations

#: The choice that stands for no answer, filling a question's choices up to four.
PAD_CHOICE = "(Do not choose this option)"
#: The letters of the four choices, in order.
LETTERS = ("A", "B", "C", "D")
