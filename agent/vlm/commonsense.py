"""What a sensible person expects about homes: where things are usually kept, and so which room a
view shows.

The simulated VLM uses this table to value directions (LSV and GSV in Explore until Confident):
a view into a kitchen is worth exploring for a mug, a view into a bathroom less so. Read the other
way, what stands in view says which room it is (`room_cue`, `room_named_by`): a toilet means a
bathroom, a bed a bedroom. Values are affinities in [0, 1]; a pair not listed gets `UNLISTED`.
"""

from __future__ import annotations

from collections.abc import Iterable

from worlds.vocabulary import FURNITURE, room_kind

UNLISTED = 0.15

#: category -> {room type: affinity}
ROOM_AFFINITY: dict[str, dict[str, float]] = {
    "mug": {"kitchen": 0.9, "dining room": 0.6, "office": 0.5, "living room": 0.4},
    "cup": {"kitchen": 0.9, "dining room": 0.7, "living room": 0.4},
    "bowl": {"kitchen": 0.9, "dining room": 0.7},
    "apple": {"kitchen": 0.9, "dining room": 0.6, "living room": 0.2},
    "bottle": {"kitchen": 0.8, "dining room": 0.5, "garage": 0.3, "bathroom": 0.3},
    "milk": {"kitchen": 0.95},
    "milk carton": {"kitchen": 0.95},
    "cereal box": {"kitchen": 0.9, "dining room": 0.4},
    "book": {"office": 0.8, "living room": 0.7, "bedroom": 0.6},
    "laptop": {"office": 0.9, "living room": 0.5, "bedroom": 0.5},
    "vase": {"living room": 0.8, "dining room": 0.6, "hallway": 0.5},
    "plant": {"living room": 0.8, "hallway": 0.5, "office": 0.4, "dining room": 0.4},
    "clock": {"living room": 0.6, "kitchen": 0.5, "bedroom": 0.5, "office": 0.5},
    "shoe": {"hallway": 0.9, "bedroom": 0.6, "garage": 0.3},
    "sock": {"bedroom": 0.9, "laundry room": 0.8, "bathroom": 0.3},
    "ball": {"garage": 0.6, "living room": 0.5, "bedroom": 0.5},
    "box": {"garage": 0.8, "office": 0.4, "hallway": 0.3},
    "toothbrush": {"bathroom": 0.95},
    "towel": {"bathroom": 0.9, "laundry room": 0.7, "bedroom": 0.3},
    "remote": {"living room": 0.9, "bedroom": 0.4},
    "keys": {"hallway": 0.8, "kitchen": 0.5, "living room": 0.4},
    "lamp": {"living room": 0.8, "bedroom": 0.8, "office": 0.7},
    "tv": {"living room": 0.9, "bedroom": 0.5},
    "stove": {"kitchen": 0.99},
    "fridge": {"kitchen": 0.99},
    "dishwasher": {"kitchen": 0.95},
    "wardrobe": {"bedroom": 0.95},
    "nightstand": {"bedroom": 0.95},
    "drawer chest": {"bedroom": 0.8, "office": 0.5},
    "cabinet": {"kitchen": 0.7, "bathroom": 0.6, "office": 0.5, "hallway": 0.4},
    "counter": {"kitchen": 0.95},
    # furniture no question asks about, which says which room a view shows (`room_cue`)
    "toilet": {"bathroom": 0.99},
    "bathtub": {"bathroom": 0.99},
    "washing machine": {"laundry room": 0.95},
    "bed": {"bedroom": 0.99},
    "sofa": {"living room": 0.9},
    "coffee table": {"living room": 0.9},
    "armchair": {"living room": 0.7, "bedroom": 0.3, "office": 0.3},
    "desk": {"office": 0.85, "bedroom": 0.4},
    "workbench": {"garage": 0.95},
    "table": {"dining room": 0.85, "kitchen": 0.6},  # a kitchen's counter and stove say more
    "bench": {"hallway": 0.85, "garage": 0.4},  # a garage's workbench says more
    "shelf": {"office": 0.5, "living room": 0.5, "hallway": 0.4, "garage": 0.4},
}

#: How much a view that leads on (through a doorway, into another room) is worth by itself.
DOORWAY_VALUE = 0.35

#: How much a view of the room the question names is worth ("… in the kitchen?": the kitchen).
NAMED_ROOM_VALUE = 0.95

#: How much a view of a room nothing in view names is worth: it might be the room looked for.
UNKNOWN_ROOM = 0.3


#: A piece of furniture names the room a view shows when its affinity to that room reaches this:
#: a bed (0.99) a bedroom, a desk (0.85) an office; a cabinet (0.7 at most) or an armchair say
#: nothing on their own.
ROOM_CUE_MIN = 0.85


def room_named_by(category: str) -> tuple[str, float] | None:
    """The room kind a piece of furniture or a fixture of ``category`` says a view shows, with its
    affinity; None for a weak cue and for small things, which are carried from room to room.

    Args:
        category: the thing's category.

    Returns:
        The room kind and affinity, or None.
    """
    if category not in FURNITURE:
        return None
    rooms = ROOM_AFFINITY.get(category, {})
    kind = max(rooms, key=rooms.__getitem__, default=None)
    return (kind, rooms[kind]) if kind is not None and rooms[kind] >= ROOM_CUE_MIN else None


def affinity(category: str | None, room_name: str) -> float:
    """How likely a thing of ``category`` is to be found in a room of this name's type.

    Args:
        category: the thing's category, or None (`UNLISTED`).
        room_name: the room's name (its type is read from it).

    Returns:
        The affinity.
    """
    if category is None:
        return UNLISTED
    return ROOM_AFFINITY.get(category, {}).get(room_kind(room_name), UNLISTED)


def room_cue(categories: Iterable[str], room_name: str) -> float:
    """How strongly things of these categories, seen together, suggest a room of this name's type:
    the strongest single cue (a toilet is enough for a bathroom). `UNLISTED` with nothing in view.
    Only the type shows: a second bedroom looks like a bedroom.

    Args:
        categories: the categories in view.
        room_name: the room's name.

    Returns:
        The cue's strength.
    """
    return max((affinity(category, room_name) for category in categories), default=UNLISTED)
