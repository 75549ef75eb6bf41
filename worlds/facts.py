"""Ground-truth facts about a home that questions are built from: what is where, and what is hidden.

An object is hidden when nothing outside can see it: it sits in a storage slot whose door or drawer
is closed, under a cover, or inside something hidden. Hidden objects make the hidden-evidence
questions ("Is there any milk carton in the fridge?") that only acting can answer; the other
questions are asked only about what the robot can see by looking.
"""

from __future__ import annotations

from worlds.home import HomeSpec
from worlds.things import Furniture, Item

#: A joint opened by less than this share of its range counts as closed.
CLOSED_SHARE = 0.05


class HomeFacts:
    """Indexes a home's things by id and answers containment and visibility questions.

    Args:
        home: the home.
    """

    def __init__(self, home: HomeSpec) -> None:
        self.home = home
        self.furniture = {f.instance_id: f for f in home.furniture}
        self.items = {o.instance_id: o for o in home.objects}

    def storage_of(self, item: Item) -> Furniture | None:
        """The storage furniture ``item`` is (directly or through its containers) inside, if any.

        Args:
            item: the object.

        Returns:
            The storage piece, or None.
        """
        access = self.access_of(item)
        return None if access is None else access[0]

    def access_of(self, item: Item) -> tuple[Furniture, str] | None:
        """The storage piece ``item`` is (directly or through its containers) inside, and the part
        (door, drawer or flap) that opens the slot it sits in; None when it is in no storage.

        Args:
            item: the object.

        Returns:
            The storage piece and the part's name, or None.
        """
        current: Item | None = item
        while current is not None and current.relation == "inside":
            parent = current.parent
            if parent in self.furniture:
                found = self.furniture[parent]
                if found.storage is None or current.slot is None:
                    return None
                return found, found.storage.slot(current.slot).access
            current = self.items.get(parent)
        return None

    def is_open(self, furniture: Furniture, part_name: str | None = None,
                joints: dict[str, float] | None = None) -> bool:
        """Whether the part (any part when None) of a storage piece is opened past `CLOSED_SHARE`,
        at the home's recorded joint states or at ``joints`` when given.

        Args:
            furniture: the storage piece.
            part_name: the part's name, or None for any.
            joints: joint states to read instead of the home's.

        Returns:
            Whether it is open.
        """
        if furniture.storage is None:
            return False
        joints = furniture.joints if joints is None else joints
        parts = [furniture.storage.part(part_name)] if part_name else list(furniture.storage.parts)
        return any(joints.get(p.name, 0.0) > p.lower + CLOSED_SHARE * (p.upper - p.lower) for p in parts)

    def is_hidden(self, item: Item) -> bool:
        """Whether the object cannot be seen without opening or lifting something.

        Args:
            item: the object.

        Returns:
            Whether it is hidden.
        """
        if item.relation == "under":
            return True
        if item.relation != "inside" or item.parent is None:
            return False
        if item.parent in self.items:
            return self.is_hidden(self.items[item.parent])
        furniture = self.furniture.get(item.parent)
        if furniture is None or furniture.storage is None or item.slot is None:
            return False
        return not self.is_open(furniture, furniture.storage.slot(item.slot).access)

    def visible_objects(self) -> list[Item]:
        """The objects that can be seen without opening or lifting anything.

        Returns:
            The objects.
        """
        return [o for o in self.home.objects if not self.is_hidden(o)]

    def storage(self) -> list[Furniture]:
        """The furniture with storage (doors, drawers or flaps).

        Returns:
            The pieces.
        """
        return [f for f in self.home.furniture if f.storage is not None]

    def appliances(self) -> list[Furniture]:
        """The furniture that can be switched on and off.

        Returns:
            The pieces.
        """
        return [f for f in self.home.furniture if "power" in f.state]
