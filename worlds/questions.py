"""Question templates of the five HM-EQA categories, and reading a question back.

The generator formats a template with words from the vocabulary; the VLM simulator parses the
question text with the same templates, the way a real VLM would understand any of these words.
The categories and their shares follow Explore until Confident (§VI): identification 16.2 %,
counting 16.0 %, existence 21.6 %, state 20.2 %, location 26.0 %.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache

from worlds import vocabulary

#: The paper's share of each question category.
CATEGORY_SHARES: dict[str, float] = {
    "identification": 0.162,
    "counting": 0.160,
    "existence": 0.216,
    "state": 0.202,
    "location": 0.260,
}

ON_OFF = ("On", "Off")
OPEN_CLOSED = ("Open", "Closed")
YES_NO = ("Yes", "No")


@dataclass(frozen=True)
class Template:
    """A question form: its category, what the answer names, and whether the evidence is hidden.

    ``asks`` is one of: colour, category, room, count, yes/no, power (on/off), door (open/closed).
    ``hidden`` templates ask about what is inside storage, seen only once it is opened.
    """

    kind: str
    asks: str
    text: str
    hidden: bool = False


TEMPLATES: tuple[Template, ...] = (
    Template("identification", "category", "Which object in the {room} is {colour}?"),
    Template("identification", "colour", "What colour is the {category} in the {room}?"),
    Template("identification", "category", "What is inside the {container} in the {room}?", hidden=True),
    Template("counting", "count", "How many {plural} are there in the {room}?"),
    Template("existence", "yes/no", "Is there a {colour} {category} in the {room}?"),
    Template("existence", "yes/no", "Is there any {category} in the {container} in the {room}?", hidden=True),
    Template("state", "power", "Is the {appliance} in the {room} on or off?"),
    Template("state", "door", "Is the {container} in the {room} open or closed?"),
    Template("location", "room", "Which room is the {colour} {category} in?"),
)


def plural(word: str) -> str:
    """English plural of a vocabulary noun (mug -> mugs, box -> boxes, toothbrush -> toothbrushes).

    Args:
        word: the noun.

    Returns:
        Its plural.
    """
    if word.endswith(("s", "x", "ch", "sh")):
        return word + "es"
    if word.endswith("y") and word[-2:-1] not in "aeiou":
        return word[:-1] + "ies"
    return word + "s"


@dataclass(frozen=True)
class ParsedQuestion:
    """What a question asks about which target; slots the question does not name are None."""

    template: Template
    category: str | None = None
    colour: str | None = None
    room: str | None = None
    container: str | None = None
    appliance: str | None = None


def _alternatives(words: list[str]) -> str:
    return "|".join(re.escape(w) for w in sorted(set(words), key=len, reverse=True))


@cache
def _patterns() -> tuple[tuple[Template, re.Pattern[str], dict[str, str]], ...]:
    """Each template as a regex over the current vocabulary, with plural forms mapped back."""
    plurals = {plural(c): c for c in vocabulary.OBJECTS}
    slots = {
        "category": list(vocabulary.OBJECTS),
        "plural": list(plurals),
        "colour": list(vocabulary.COLOURS),
        "room": list(vocabulary.room_names()),
        "container": list(vocabulary.STORAGE_CATEGORIES),
        "appliance": list(vocabulary.APPLIANCES),
    }
    compiled = []
    for template in TEMPLATES:
        regex = re.escape(template.text)
        for slot, words in slots.items():
            regex = regex.replace(re.escape("{" + slot + "}"), f"(?P<{slot}>{_alternatives(words)})")
        compiled.append((template, re.compile(f"^{regex}$", re.IGNORECASE), plurals))
    return tuple(compiled)


def parse_question(text: str) -> ParsedQuestion | None:
    """Read a question with the vocabulary; None when it matches no template.

    Args:
        text: the question.

    Returns:
        The template and its slots, or None.
    """
    for template, pattern, plurals in _patterns():
        match = pattern.match(text.strip())
        if match:
            slots = {k: v.lower() for k, v in match.groupdict().items()}
            if "plural" in slots:
                slots["category"] = plurals[slots.pop("plural")]
            return ParsedQuestion(template, **slots)
    return None


def format_question(template: Template, **slots: str) -> str:
    """The template's text with its slots filled (``category`` also fills ``{plural}``).

    Args:
        template: the template.
        **slots: the slots' values.

    Returns:
        The question.
    """
    if "category" in slots:
        slots = {**slots, "plural": plural(slots["category"])}
    return template.text.format(**slots)
