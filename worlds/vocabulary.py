"""The words homes are made of.

The generator draws every category, colour and room type from here, and the VLM simulator parses
questions (`worlds.questions`) with the same words, the way a real VLM would understand them.
"""

from __future__ import annotations

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
    "brown": (0.5, 0.32, 0.16, 1.0),
    "grey": (0.5, 0.5, 0.52, 1.0),
    "pink": (0.95, 0.55, 0.7, 1.0),
}

#: Kinds of room. A home has at most one of each, except those in `ROOM_REPEATS`.
ROOM_TYPES = (
    "kitchen", "living room", "bedroom", "bathroom", "dining room", "office", "hallway", "garage", "laundry room",
)
#: Room kinds a home may have several of, and how many at most. Later ones are named with an
#: ordinal ("second bedroom"), so every room's name is unique and still an English phrase.
ROOM_REPEATS: dict[str, int] = {"bedroom": 3, "bathroom": 2}
_ORDINALS = ("", "second ", "third ")


def room_name(kind: str, index: int) -> str:
    """The name of the ``index``-th room (0-based) of ``kind``: 'bedroom', 'second bedroom', ...

    Args:
        kind: the room's kind.
        index: which of that kind.

    Returns:
        The name.
    """
    return _ORDINALS[index] + kind


def room_names() -> tuple[str, ...]:
    """Every name a room can carry, so questions can name any room of any home.

    Returns:
        The names.
    """
    return tuple(room_name(kind, i) for kind in ROOM_TYPES for i in range(ROOM_REPEATS.get(kind, 1)))


def room_kind(name: str) -> str:
    """The kind of the room called ``name`` ('second bedroom' -> 'bedroom').

    Args:
        name: the room's name.

    Returns:
        The kind.
    """
    for ordinal in _ORDINALS[1:]:
        if name.startswith(ordinal):
            return name[len(ordinal):]
    return name


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
    "cup": ("cylinder", (0.04, 0.09)),
    "plate": ("cylinder", (0.12, 0.02)),
    "milk carton": ("box", (0.07, 0.07, 0.2)),
    "cereal box": ("box", (0.19, 0.07, 0.28)),
    "can": ("cylinder", (0.033, 0.12)),
    "jar": ("cylinder", (0.045, 0.12)),
    "toothbrush": ("box", (0.02, 0.19, 0.02)),
    "towel": ("box", (0.4, 0.3, 0.03)),
    "soap": ("box", (0.09, 0.06, 0.03)),
    "shampoo": ("cylinder", (0.035, 0.2)),
    "sock": ("box", (0.1, 0.22, 0.03)),
    "shirt": ("box", (0.3, 0.25, 0.04)),
    "remote": ("box", (0.05, 0.18, 0.02)),
    "keys": ("box", (0.08, 0.05, 0.02)),
    "phone": ("box", (0.075, 0.15, 0.01)),
    "wallet": ("box", (0.11, 0.09, 0.02)),
    "glasses": ("box", (0.14, 0.05, 0.04)),
    "pen": ("box", (0.14, 0.012, 0.012)),
    "ring": ("cylinder", (0.012, 0.006)),
    "candle": ("cylinder", (0.035, 0.12)),
    "toy car": ("box", (0.12, 0.06, 0.05)),
    "teddy bear": ("box", (0.18, 0.14, 0.25)),
    "basket": ("cylinder", (0.16, 0.2)),
    "jewelry box": ("box", (0.12, 0.09, 0.06)),
    "toolbox": ("box", (0.4, 0.2, 0.2)),
    "hammer": ("box", (0.3, 0.1, 0.03)),
    "detergent": ("box", (0.2, 0.12, 0.28)),
    "table lamp": ("cylinder", (0.1, 0.45)),
}

#: Where each object is usually found (room kinds); objects are mostly drawn to suit their room.
OBJECT_ROOMS: dict[str, tuple[str, ...]] = {
    "mug": ("kitchen", "dining room", "office", "living room"),
    "book": ("office", "living room", "bedroom"),
    "apple": ("kitchen", "dining room"),
    "bottle": ("kitchen", "dining room", "garage", "bathroom"),
    "vase": ("living room", "dining room", "hallway"),
    "laptop": ("office", "living room", "bedroom"),
    "clock": ("living room", "kitchen", "bedroom", "office"),
    "bowl": ("kitchen", "dining room"),
    "shoe": ("hallway", "bedroom", "garage"),
    "ball": ("garage", "living room", "bedroom"),
    "box": ("garage", "office", "hallway", "laundry room", "bedroom"),
    "plant": ("living room", "hallway", "office", "dining room"),
    "cup": ("kitchen", "dining room", "living room"),
    "plate": ("kitchen", "dining room"),
    "milk carton": ("kitchen",),
    "cereal box": ("kitchen",),
    "can": ("kitchen", "garage"),
    "jar": ("kitchen",),
    "toothbrush": ("bathroom",),
    "towel": ("bathroom", "laundry room", "bedroom", "kitchen"),
    "soap": ("bathroom", "laundry room"),
    "shampoo": ("bathroom",),
    "sock": ("bedroom", "laundry room"),
    "shirt": ("bedroom", "laundry room"),
    "remote": ("living room", "bedroom"),
    "keys": ("hallway", "kitchen", "living room"),
    "phone": ("living room", "bedroom", "office"),
    "wallet": ("hallway", "bedroom"),
    "glasses": ("bedroom", "office", "living room"),
    "pen": ("office",),
    "ring": ("bedroom", "bathroom"),
    "candle": ("dining room", "living room"),
    "toy car": ("bedroom", "living room"),
    "teddy bear": ("bedroom",),
    "basket": ("laundry room", "bathroom", "bedroom"),
    "jewelry box": ("bedroom",),
    "toolbox": ("garage",),
    "hammer": ("garage",),
    "detergent": ("laundry room",),
    "table lamp": ("bedroom", "living room", "office"),
}

#: Objects that hold others inside them (a box, a bowl): their inside is their size less the walls.
CONTAINERS = ("box", "bowl", "basket", "jewelry box", "toolbox")
#: Objects that can hide a smaller one under them: a towel laid over it, a bowl or box upturned.
COVERS = ("towel", "bowl", "box")

#: Furniture: category -> size (x along the wall, y away from it, z) in metres and the room kinds it
#: belongs in. Storage furniture (`STORAGE_CATEGORIES`) opens; its parts come from worlds.storage.
FURNITURE: dict[str, tuple[tuple[float, float, float], tuple[str, ...]]] = {
    "table": ((1.2, 0.8, 0.75), ("kitchen", "dining room")),
    "sofa": ((1.9, 0.85, 0.8), ("living room",)),
    "armchair": ((0.8, 0.8, 0.85), ("living room", "bedroom", "office")),
    "coffee table": ((1.0, 0.55, 0.42), ("living room",)),
    "bed": ((1.5, 2.0, 0.55), ("bedroom",)),
    "desk": ((1.3, 0.7, 0.75), ("office", "bedroom")),
    "shelf": ((1.0, 0.35, 1.2), ("office", "living room", "hallway", "garage")),
    "bench": ((1.0, 0.4, 0.45), ("hallway", "garage")),
    "workbench": ((1.6, 0.7, 0.9), ("garage",)),
    "washing machine": ((0.6, 0.6, 0.85), ("laundry room",)),
    "bathtub": ((1.6, 0.75, 0.55), ("bathroom",)),
    "toilet": ((0.4, 0.65, 0.75), ("bathroom",)),
    "tv": ((1.2, 0.4, 1.15), ("living room", "bedroom")),
    "lamp": ((0.4, 0.4, 1.6), ("living room", "bedroom", "office")),
    "stove": ((0.6, 0.62, 0.9), ("kitchen",)),
    "curtain": ((1.6, 0.08, 2.3), ("living room", "bedroom", "dining room", "office")),
    "counter": ((1.6, 0.6, 0.9), ("kitchen",)),
    "fridge": ((0.7, 0.7, 1.8), ("kitchen",)),
    "dishwasher": ((0.6, 0.6, 0.85), ("kitchen",)),
    "cabinet": ((0.9, 0.45, 0.9), ("kitchen", "bathroom", "office", "living room", "hallway", "dining room",
                                   "garage", "laundry room")),
    "wardrobe": ((1.2, 0.6, 2.0), ("bedroom",)),
    "nightstand": ((0.45, 0.4, 0.55), ("bedroom",)),
    "drawer chest": ((0.9, 0.5, 1.0), ("bedroom", "office")),
}

#: Furniture with doors, drawers or flaps that can hide things ("Is there any milk in the fridge?").
STORAGE_CATEGORIES = ("cabinet", "counter", "drawer chest", "wardrobe", "nightstand", "fridge", "dishwasher")
#: Things with a visible power state ("Is the lamp in the bedroom on or off?"): a lit lamp shade,
#: a lit screen, red burners. A "lamp" is furniture standing on the floor, a "table lamp" an object.
APPLIANCES = ("lamp", "table lamp", "tv", "stove")
#: Furniture nothing is put on top of: too tall, not flat, or hot.
NO_TOP = ("wardrobe", "fridge", "tv", "lamp", "stove", "curtain", "toilet", "bathtub")
#: What a room of each kind gets first, in this order, before pieces drawn from the rest.
ESSENTIALS: dict[str, tuple[str, ...]] = {
    "kitchen": ("counter", "fridge", "stove"),
    "living room": ("sofa", "tv", "coffee table"),
    "bedroom": ("bed", "wardrobe", "nightstand"),
    "bathroom": ("toilet", "cabinet", "bathtub"),
    "dining room": ("table",),
    "office": ("desk", "drawer chest"),
    "hallway": ("shelf",),
    "garage": ("workbench", "cabinet"),
    "laundry room": ("washing machine", "cabinet"),
}
