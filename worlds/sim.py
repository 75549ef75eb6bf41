"""One simulated home in its own PyBullet DIRECT client: reset, observe, move the base, open things.

The robot is kinematic: moving it means teleporting its body in short steps and asking, after each
step, whether it now touches anything but the floor. Storage parts are moved the same way, by
setting their joints; small objects are static bodies, so an object standing in a drawer is moved
by the drawer's displacement whenever the drawer's state is set (exact and free of physics
settling; a fixed constraint would need dynamic objects). PyBullet is not thread-safe, so a `World`
must be created and used from one thread only (the world server's serving thread).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np
import pybullet as p

from worlds.camera import Frame, render
from worlds.facts import HomeFacts
from worlds.home import HomeSpec, generate_home
from worlds.robot import ROBOT_HEIGHT, ROBOT_RADIUS, CameraConfig
from worlds.scenario import Scenario, make_scenario
from worlds.scene import BuiltScene, build_scene, floor_bodies
from worlds.things import Label

log = logging.getLogger(__name__)

#: The longest straight step between two collision checks, in metres.
MAX_STEP = 0.05

#: Where the robot's body waits while its head camera renders: its top would fill the view.
_OUT_OF_SIGHT = (0.0, 0.0, -100.0)
_ROBOT_RGBA = (0.3, 0.35, 0.4, 1.0)

Pose = tuple[float, float, float]


@dataclass(frozen=True)
class MoveResult:
    """Where a move_base ended, whether it got to the end of its path, and what it bumped into."""

    base_pose: Pose
    reached: bool
    contact: Label | None
    travelled_m: float
    contact_point: tuple[float, float] | None = None  # where on the obstacle the body touched it


class World:
    """A home, its scenario and the robot in it."""

    def __init__(self, camera: CameraConfig) -> None:
        self.camera = camera
        self.client = p.connect(p.DIRECT)
        self.home: HomeSpec | None = None
        self.scenario: Scenario | None = None
        self.base_pose: Pose = (0.0, 0.0, 0.0)
        self.observations = 0
        self._built = BuiltScene()
        self._floors: set[int] = set()
        self._robot = -1

    def reset(self, seed: int, n_rooms: int | None = None) -> Scenario:
        """Build the home of ``seed`` from scratch and put the robot at its scenario's start pose."""
        home = generate_home(seed, n_rooms)
        return self.start(home, make_scenario(home, seed))

    def start(self, home: HomeSpec, scenario: Scenario) -> Scenario:
        """Build ``home`` and put the robot at ``scenario``'s start pose."""
        self.build(home)
        self.scenario = scenario
        self.place(scenario.start_pose)
        log.info("home %d: %d rooms, %.1f m², question %r", home.seed, len(home.rooms), home.area_m2, scenario.question)
        return scenario

    def build(self, home: HomeSpec) -> None:
        """Replace the simulation with ``home`` (its storage furniture articulated) and the robot."""
        p.resetSimulation(physicsClientId=self.client)
        self._built = build_scene(home, self.client)
        self._floors = floor_bodies(self._built.labels)
        self._robot = self._add_robot()
        self._facts = HomeFacts(home)
        self.home, self.scenario, self.observations = home, None, 0

    def set_part_state(self, furniture_id: int, part_name: str, value: float) -> None:
        """Set a door, drawer or flap of a storage piece; whatever stands in a drawer moves with it."""
        piece = self._built.storage.get(furniture_id)
        if piece is None:
            raise ValueError(f"furniture_id: {furniture_id} is not a storage piece")
        model = piece.placement.model
        try:
            part = model.part(part_name)
        except KeyError as error:
            raise ValueError(f"part_name: {error.args[0]}") from None
        if not (math.isfinite(value) and part.lower <= value <= part.upper):
            raise ValueError(f"value: {value} is outside [{part.lower}, {part.upper}] for {part_name}")
        link = piece.links[part_name]
        before = p.getJointState(piece.body, link, physicsClientId=self.client)[0]
        p.resetJointState(piece.body, link, value, physicsClientId=self.client)
        if part.kind != "drawer":
            return
        yaw = piece.placement.pose[3]
        shift = (value - before) * np.array([math.sin(yaw), -math.cos(yaw), 0.0])  # local -y in the world
        for item_id in self._riders(furniture_id, part_name):
            body = self._built.items[item_id]
            position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
            p.resetBasePositionAndOrientation(body, (np.asarray(position) + shift).tolist(), orientation,
                                              physicsClientId=self.client)

    def _riders(self, furniture_id: int, drawer: str) -> set[int]:
        """Objects standing in ``drawer``'s slots, and whatever is in, under or on them, transitively."""
        placement = self._built.storage[furniture_id].placement
        moving = {slot.name for slot in placement.model.slots if slot.part == drawer}
        riders = {item for item, slot in placement.contents if slot in moving}
        assert self.home is not None, "storage exists only in a built home"
        carried: dict[int, list[int]] = {}
        for item in self.home.objects:
            if item.parent is not None:
                carried.setdefault(item.parent, []).append(item.instance_id)
        stack = list(riders)
        while stack:
            for child in carried.get(stack.pop(), ()):
                if child not in riders:
                    riders.add(child)
                    stack.append(child)
        return riders

    def object_position(self, instance_id: int) -> tuple[float, float, float]:
        """Where a small object's centre is now."""
        position, _ = p.getBasePositionAndOrientation(self._built.items[instance_id], physicsClientId=self.client)
        return (float(position[0]), float(position[1]), float(position[2]))

    def part_states(self) -> dict[int, dict[str, float]]:
        """Furniture id -> part name -> joint value, for every storage piece."""
        return {
            furniture_id: {
                part.name: float(p.getJointState(piece.body, piece.links[part.name], physicsClientId=self.client)[0])
                for part in piece.placement.model.parts
            }
            for furniture_id, piece in self._built.storage.items()
        }

    def _add_robot(self) -> int:
        shape = {"radius": ROBOT_RADIUS, "physicsClientId": self.client}
        collision = p.createCollisionShape(p.GEOM_CYLINDER, height=ROBOT_HEIGHT, **shape)
        visual = p.createVisualShape(p.GEOM_CYLINDER, length=ROBOT_HEIGHT, rgbaColor=_ROBOT_RGBA, **shape)
        return p.createMultiBody(0.0, collision, visual, [0.0, 0.0, ROBOT_HEIGHT / 2], physicsClientId=self.client)

    def place(self, pose: Pose) -> None:
        """Teleport the robot, without any collision check."""
        x, y, yaw = pose
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        orientation = p.getQuaternionFromEuler((0.0, 0.0, yaw))
        position = (x, y, ROBOT_HEIGHT / 2)
        p.resetBasePositionAndOrientation(self._robot, position, orientation, physicsClientId=self.client)
        self.base_pose = (float(x), float(y), float(yaw))

    def observe(self) -> Frame:
        """Render the head camera, with the robot's own body stepped out of the picture meanwhile."""
        self.observations += 1
        pose = self.base_pose
        p.resetBasePositionAndOrientation(self._robot, _OUT_OF_SIGHT, (0, 0, 0, 1), physicsClientId=self.client)
        try:
            frame = render(self.client, self.camera, pose, self._built.labels)
        finally:
            self.place(pose)
        joints = self.part_states()
        return replace(frame, labels=[self._visible_facts(label, joints) for label in frame.labels])

    def _visible_facts(self, label: Label, joints: dict[int, dict[str, float]]) -> Label:
        """The label with what the camera shows of the thing now: a switch or door ``state``, and
        the kind of storage it is seen ``inside``. Doors may have moved since the home was built."""
        facts, thing_id = self._facts, label["id"]
        extra: dict[str, str] = {}
        furniture = facts.furniture.get(thing_id)
        item = facts.items.get(thing_id)
        switches = (furniture or item).state if (furniture or item) is not None else {}
        if switches:
            extra["state"] = next(iter(switches.values()))
        if furniture is not None and furniture.storage is not None:
            extra["state"] = "open" if facts.is_open(furniture, joints=joints[thing_id]) else "closed"
        if item is not None and (storage := facts.storage_of(item)) is not None:
            extra["inside"] = storage.category
        return {**label, **extra}

    def contact(self) -> Label | None:
        """The label of what the robot body touches now (the deepest contact), ignoring floors."""
        touching = self._touching()
        return None if touching is None else touching[0]

    def _touching(self) -> tuple[Label, tuple[float, float]] | None:
        """The deepest contact's label (a storage part's own) and its (x, y) on the obstacle, ignoring floors."""
        x, y, _ = self.base_pose
        lo, hi = (x - ROBOT_RADIUS, y - ROBOT_RADIUS, 0.0), (x + ROBOT_RADIUS, y + ROBOT_RADIUS, ROBOT_HEIGHT)
        deepest: tuple[float, tuple[int, int], tuple[float, float]] | None = None
        for body in {body for body, _ in p.getOverlappingObjects(lo, hi, physicsClientId=self.client) or ()}:
            if body == self._robot or body in self._floors:
                continue
            for point in p.getClosestPoints(self._robot, body, 0.0, physicsClientId=self.client):
                if deepest is None or point[8] < deepest[0]:
                    deepest = (point[8], (body, point[4]), (float(point[6][0]), float(point[6][1])))
        if deepest is None:
            return None
        labels = self._built.labels
        return labels.get(deepest[1], labels[(deepest[1][0], -1)]), deepest[2]

    def move_base(self, path: list[tuple[float, float]], yaw: float | None = None) -> MoveResult:
        """Follow the polyline in steps of at most `MAX_STEP`, then turn; stop before any contact."""
        x, y, heading = self.base_pose
        travelled = 0.0
        for tx, ty in path:
            length = math.hypot(tx - x, ty - y)
            steps = math.ceil(length / MAX_STEP)
            for k in range(1, steps + 1):
                nx, ny = x + (tx - x) * k / steps, y + (ty - y) * k / steps
                self.place((nx, ny, heading))
                hit = self._touching()
                if hit is not None:
                    previous = k - 1
                    self.place((x + (tx - x) * previous / steps, y + (ty - y) * previous / steps, heading))
                    return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
                travelled += length / steps
            x, y = tx, ty
        if yaw is not None:
            self.place((x, y, yaw))
            hit = self._touching()
            if hit is not None:
                self.place((x, y, heading))
                return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
        return MoveResult(self.base_pose, True, None, travelled)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)
