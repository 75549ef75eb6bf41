"""Which storage a question asks what is in, and which room it stands in, read off the question.

Both the act branch (`behaviours.look_inside`: what to open) and the approach to storage seen from
afar (`behaviours.approach_storage`: where to go) act on the same reading of the question text.
"""

from __future__ import annotations

import re

from agent.perception.instances import STORAGE_CATEGORIES

_STORAGE_WORDS = "|".join(re.escape(w) for w in sorted(STORAGE_CATEGORIES, key=len, reverse=True))


def storage_in_question(question: str) -> str | None:
    """The kind of storage the question asks what is in ("in the fridge", "inside the cabinet").

    Args:
        question: the question.

    Returns:
        The storage word, or None.
    """
    found = re.search(rf"\b(?:in|inside) the ({_STORAGE_WORDS})\b", question.lower())
    return found.group(1) if found else None


def room_in_question(question: str) -> str | None:
    """The room the storage the question asks about stands in ("in the cabinet in the laundry room").

    Args:
        question: the question.

    Returns:
        The room's name, or None.
    """
    found = re.search(rf"\b(?:in|inside) the (?:{_STORAGE_WORDS}) in the ([a-z ]+?)\s*\?*$", question.lower().strip())
    return found.group(1) if found else None
