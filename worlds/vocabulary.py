"""The words homes are made of, and the question templates built from them.

The generator draws every category, colour and room type from here, and the VLM simulator parses
questions with the same vocabulary, the way a real VLM would understand any of these words.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: Colour name -> RGBA used to render it.
COLOURS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.85, 0.12, 0.12, 1.0),
    "green": (0.15, 0.65, 0.2, 1.0),
    "blue": (0.15, 0.3, 0.85, 1.0),
    "yellow": (0.95, 0.85, 0.1, 1.0),
    "white": (0.95, 0.95, 0.95, 1.0),
    "black": (0.08, 0.08, 0.08, 1.0),
    "orange": (0.95, 0.5, 0.05, 1.0),
    "purple": (0.55, 0.2, 0.7, 1.0),
}

ROOM_TYPES = ("kitchen", "living room", "bedroom", "bathroom", "office", "dining room", "hallway")

#: Small objects: category -> (shape, size in metres). Shapes: box (x, y, z), cylinder (r, h), sphere (r).
OBJECTS: dict[str, tuple[str, tuple[float, ...]]] = {
    "mug": ("cylinder", (0.05, 0.11)),
    "book": ("box", (0.16, 0.23, 0.04)),
    "apple": ("sphere", (0.05,)),
    "bottle": ("cylinder", (0.04, 0.26)),
    "vase": ("cylinder", (0.07, 0.3)),
    "laptop": ("box", (0.33, 0.23, 0.03)),
    "clock": ("cylinder", (0.12, 0.05)),
    "bowl": ("cylinder", (0.09, 0.07)),
    "shoe": ("box", (0.28, 0.1, 0.1)),
    "ball": ("sphere", (0.11,)),
    "box": ("box", (0.25, 0.2, 0.18)),
    "plant": ("cylinder", (0.12, 0.45)),
}

#: Furniture: category -> size (x, y, z) in metres and the room types it belongs in.
FURNITURE: dict[str, tuple[tuple[float, float, float], tuple[str, ...]]] = {
    "table": ((1.2, 0.8, 0.75), ("kitchen", "dining room", "living room")),
    "counter": ((1.6, 0.6, 0.9), ("kitchen",)),
    "sofa": ((1.9, 0.85, 0.8), ("living room",)),
    "bed": ((2.0, 1.5, 0.55), ("bedroom",)),
    "desk": ((1.3, 0.7, 0.75), ("office", "bedroom")),
    "shelf": ((1.0, 0.35, 1.2), ("office", "living room", "hallway")),
    "cabinet": ((0.9, 0.45, 0.9), ("bathroom", "kitchen", "hallway", "dining room")),
}

PAD_CHOICE = "(Do not choose this option)"
LETTERS = ("A", "B", "C", "D")


@dataclass(frozen=True)
class Template:
    """A question form: what it asks for, and the attributes that pick its target."""

    kind: str  # the paper's category: identification, existence, state, location, counting
    asks: str  # the attribute the answer names: colour, room, category or yes/no
    text: str  # a str.format pattern over category, colour and room

    def pattern(self) -> re.Pattern[str]:
        regex = re.escape(self.text)
        for slot, words in (("category", OBJECTS), ("colour", COLOURS), ("room", ROOM_TYPES)):
            alternatives = "|".join(re.escape(w) for w in sorted(words, key=len, reverse=True))
            regex = regex.replace(re.escape("{" + slot + "}"), f"(?P<{slot}>{alternatives})")
        return re.compile(f"^{regex}$", re.IGNORECASE)


TEMPLATES: tuple[Template, ...] = (
    Template("identification", "category", "Which object in the {room} is {colour}?"),
    Template("identification", "colour", "What colour is the {category} in the {room}?"),
    Template("existence", "yes/no", "Is there a {colour} {category} in the {room}?"),
    Template("location", "room", "Which room is the {colour} {category} in?"),
)


@dataclass(frozen=True)
class ParsedQuestion:
    """What a question asks (``asks``) about which target (attributes named in it)."""

    template: Template
    category: str | None
    colour: str | None
    room: str | None


def parse_question(text: str) -> ParsedQuestion | None:
    """Read a question with the vocabulary; None when it matches no template."""
    for template in TEMPLATES:
        match = template.pattern().match(text.strip())
        if match:
            slots = {k: v.lower() for k, v in match.groupdict().items()}
            return ParsedQuestion(template, slots.get("category"), slots.get("colour"), slots.get("room"))
    return None


#: Furniture with doors or drawers that can hide things ("Is there any milk in the fridge?").
STORAGE_CATEGORIES = ("cabinet", "drawer chest", "wardrobe", "nightstand", "fridge", "dishwasher", "counter")

#: Things with a visible power state ("Is the lamp in the bedroom on or off?").
APPLIANCES = ("lamp", "tv", "stove")

#: Words that set apart two rooms of one type ("second bedroom").
ROOM_ORDINALS = ("second", "third")


def room_names() -> tuple[str, ...]:
    """Every name a room can have: its type, or an ordinal and its type when a type repeats."""
    return ROOM_TYPES + tuple(f"{ordinal} {room}" for ordinal in ROOM_ORDINALS for room in ROOM_TYPES)
