"""One simulated home in its own PyBullet DIRECT client: reset, observe, move the base, use the arm.

The base is kinematic: moving it means teleporting the robot in short steps and asking, after each
step, whether its base touches anything but the floor (and, when the arm is out or holds something,
whether the arm or what it holds does). Storage parts are set directly by `World.set_part_state`,
or moved by the arm through physics (`worlds.arm`); small objects are static bodies, so an object
standing in a drawer is moved by the drawer's displacement whenever the drawer moves
(`worlds.riders`: exact and free of physics settling). The arm, stowed, stays inside the base's
cylinder and out of every camera's picture, so a robot that never uses it sees and bumps into the
world exactly as the disc alone did. PyBullet is not thread-safe, so a `World` must be created and
used from one thread only (the world server's serving thread).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np
import pybullet as p

from worlds.arm import Arm, Touch, TrajectoryRun
from worlds.camera import Frame, render, render_at
from worlds.facts import CLOSED_SHARE, HomeFacts
from worlds.home import HomeSpec, generate_home
from worlds.riders import Riders
from worlds.robot import ROBOT_HEIGHT, ROBOT_RADIUS, CameraConfig
from worlds.robot_arm import CAMERAS, WRIST_CAMERA, WRIST_CAMERA_FRAME, arm_spec, homebot_urdf
from worlds.scenario import Scenario, make_scenario
from worlds.scene import BuiltScene, StorageBody, build_scene, floor_bodies, link_indices, urdf_file
from worlds.tabletop import build_tabletop
from worlds.tabletop_scene import TabletopScene
from worlds.things import Furniture, Label

log = logging.getLogger(__name__)

#: The longest straight step between two collision checks, in metres.
MAX_STEP = 0.05

#: Where the robot's body waits while a camera renders: the robot never appears in its own frames.
_OUT_OF_SIGHT = (0.0, 0.0, -100.0)
#: How far (rad or m) a trajectory's first sample may be from where the arm is, beyond one sample's travel.
START_TOLERANCE = 0.05
#: A tabletop robot starts this far from the table's front edge, facing it.
TABLE_GAP = 0.03

Pose = tuple[float, float, float]


@dataclass(frozen=True)
class MoveResult:
    """Where a move_base ended, whether it got to the end of its path, and what it bumped into."""

    base_pose: Pose
    reached: bool
    contact: Label | None
    travelled_m: float
    contact_point: tuple[float, float] | None = None  # where on the obstacle the body touched it


@dataclass(frozen=True)
class ArmState:
    """The lift and arm joints (`arm_spec` order), the TCP's 4x4 world pose, the gripper's opening
    (m) and what it holds: the thing's label, with ``link`` naming the part of a storage piece held."""

    positions: np.ndarray
    tcp_pose: np.ndarray
    gripper_width: float
    held: Label | None
    stowed: bool


@dataclass(frozen=True)
class TrajectoryResult:
    """How an arm trajectory went (`worlds.arm.TrajectoryRun`), contacts as labels of what was
    touched, each with ``robot_link`` (the arm's link) and ``link`` (a storage part's own, else None)."""

    run: TrajectoryRun
    contacts: list[Label]


class World:
    """A home (or a tabletop), its scenario and the robot in it."""

    def __init__(self, camera: CameraConfig, wrist_camera: CameraConfig = WRIST_CAMERA) -> None:
        self.camera = camera
        self.wrist_camera = wrist_camera
        self.client = p.connect(p.DIRECT)
        self.home: HomeSpec | None = None
        self.tabletop: TabletopScene | None = None
        self.scenario: Scenario | None = None
        self.base_pose: Pose = (0.0, 0.0, 0.0)
        self.observations = 0
        self._built = BuiltScene()
        self._floors: set[int] = set()
        self._robot = -1
        self._base = -1
        self._facts: HomeFacts | None = None
        self._parts: dict[int, tuple[int, str]] = {}  # a storage part's instance id -> (its piece's id, its name)
        self._arm: Arm | None = None
        self._riders: Riders | None = None

    @property
    def ready(self) -> bool:
        """Whether a home or a tabletop has been built."""
        return self.home is not None or self.tabletop is not None

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
        self._add_robot()
        self._facts = HomeFacts(home)
        self._parts = {piece.placement.part_ids()[part.name]: (piece_id, part.name)
                       for piece_id, piece in self._built.storage.items() for part in piece.placement.model.parts}
        self._riders = Riders(self.client, self._built, {item.instance_id: item.parent for item in home.objects})
        self.home, self.tabletop, self.scenario, self.observations = home, None, None, 0

    def start_tabletop(self, scene: TabletopScene, base_pose: Pose | None = None) -> Pose:
        """Replace the simulation with a tabletop ``scene`` and the robot, by default in front of the
        table's middle facing it (+y); returns the robot's pose."""
        p.resetSimulation(physicsClientId=self.client)
        labels = build_tabletop(self.client, scene)
        placements = {placement.furniture_id: placement for _, placement in scene.storage}
        objects = {obj.instance_id for obj in scene.objects}
        built = BuiltScene(labels)
        for (body, link), label in labels.items():
            if link == -1 and label["id"] in placements:
                built.storage[label["id"]] = StorageBody(body, placements[label["id"]], link_indices(self.client, body))
            elif link == -1 and label["id"] in objects:
                built.items[label["id"]] = body
        self._built, self._floors, self._facts = built, set(), None
        self._add_robot()
        self._riders = Riders(self.client, built, {obj.instance_id: obj.parent for obj in scene.objects})
        self.home, self.tabletop, self.scenario, self.observations = None, scene, None, 0
        if base_pose is None:
            base_pose = (0.0, -(scene.table_size[1] / 2 + ROBOT_RADIUS + TABLE_GAP), math.pi / 2)
        self.place(base_pose)
        return self.base_pose

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
        p.resetJointState(piece.body, piece.links[part_name], value, physicsClientId=self.client)
        self.riders.sync()

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

    def _add_robot(self) -> None:
        """Load the whole robot (`homebot_urdf`) with its arm stowed, and the base's contact body.

        The robot's base is fixed: it only moves when `place` teleports it. Its contacts are asked of
        a separate static cylinder of the same size (``_base``): PyBullet wraps a URDF link's shapes
        in a compound whose closest points differ from the plain cylinder's by millimetres, and the
        base must bump into things exactly where it always did. The URDF base's own collisions are
        off, and the contact cylinder ignores the arm inside it.
        """
        path = urdf_file(homebot_urdf(self.camera))
        self._robot = p.loadURDF(str(path), useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE,
                                 physicsClientId=self.client)
        p.setCollisionFilterGroupMask(self._robot, -1, 0, 0, physicsClientId=self.client)
        shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=ROBOT_RADIUS, height=ROBOT_HEIGHT,
                                       physicsClientId=self.client)
        self._base = p.createMultiBody(0.0, shape, -1, [0.0, 0.0, ROBOT_HEIGHT / 2], physicsClientId=self.client)
        for link in range(-1, p.getNumJoints(self._robot, physicsClientId=self.client)):
            p.setCollisionFilterPair(self._base, self._robot, -1, link, 0, physicsClientId=self.client)
        self._arm = Arm(self.client, self._robot, arm_spec())
        self._arm.stow()

    @property
    def arm(self) -> Arm:
        assert self._arm is not None, "the robot exists only in a built scene"
        return self._arm

    @property
    def riders(self) -> Riders:
        assert self._riders is not None, "objects ride on things only in a built scene"
        return self._riders

    def place(self, pose: Pose) -> None:
        """Teleport the robot, without any collision check."""
        x, y, yaw = pose
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        orientation = p.getQuaternionFromEuler((0.0, 0.0, yaw))
        p.resetBasePositionAndOrientation(self._robot, (x, y, 0.0), orientation, physicsClientId=self.client)
        p.resetBasePositionAndOrientation(self._base, (x, y, ROBOT_HEIGHT / 2), orientation,
                                          physicsClientId=self.client)
        self.base_pose = (float(x), float(y), float(yaw))

    def _hide_robot(self) -> None:
        """Step the robot out of the world (until the next `place`): out of cameras' and rays' way."""
        for body in (self._robot, self._base):
            p.resetBasePositionAndOrientation(body, _OUT_OF_SIGHT, (0, 0, 0, 1), physicsClientId=self.client)

    def observe(self, camera: str = "head") -> Frame:
        """Render the head or the wrist camera, with the robot's own body stepped out of the picture
        meanwhile (what the hand holds stays in it)."""
        if camera not in CAMERAS:
            raise ValueError(f"camera: {camera!r} is not one of {CAMERAS}")
        self.observations += 1
        pose = self.base_pose
        wrist = self.arm.link_pose(WRIST_CAMERA_FRAME) if camera == "wrist" else None
        self._hide_robot()
        try:
            if wrist is None:
                frame = render(self.client, self.camera, pose, self._built.labels)
            else:
                frame = render_at(self.client, self.wrist_camera, wrist, self._built.labels)
        finally:
            self.place(pose)
        joints = self.part_states()
        in_frame = {label["id"] for label in frame.labels}
        return replace(frame, labels=[self._visible_facts(label, joints, in_frame) for label in frame.labels])

    def _visible_facts(self, label: Label, joints: dict[int, dict[str, float]], in_frame: set[int]) -> Label:
        """The label with what the camera shows of the thing now: a switch's ``state``, whether a
        storage piece or one of its doors and drawers stands open, and the kind of storage it is
        seen ``inside``. Doors may have moved since the home was built.

        ``inside`` is only given when the frame shows the storage's interior around the thing: the
        part that opens its slot stands open (past `CLOSED_SHARE` of its travel) and the piece
        itself, its carcass or that open part, is in the same frame (``in_frame``: the ids of the
        frame). A carton glimpsed with no fridge in view, or behind a door shut since, is just a
        carton: a camera cannot tell it is in a fridge."""
        facts, thing_id = self._facts, label["id"]
        if facts is None:  # a tabletop: only its storage has a state
            piece = self._built.storage.get(thing_id)
            if piece is None:
                return label
            parts = piece.placement.model.parts
            opened = any(joints[thing_id][q.name] > q.lower + CLOSED_SHARE * (q.upper - q.lower) for q in parts)
            return {**label, "state": "open" if opened else "closed"}
        extra: dict[str, str] = {}
        furniture = facts.furniture.get(thing_id)
        item = facts.items.get(thing_id)
        switches = (furniture or item).state if (furniture or item) is not None else {}
        if switches:
            extra["state"] = next(iter(switches.values()))
        if furniture is not None and furniture.storage is not None:
            extra["state"] = "open" if facts.is_open(furniture, joints=joints[thing_id]) else "closed"
        part = self._parts.get(thing_id)
        if part is not None:  # a door or drawer: whether it stands open shows
            piece = facts.furniture[part[0]]
            extra["state"] = "open" if facts.is_open(piece, part[1], joints=joints[part[0]]) else "closed"
        access = facts.access_of(item) if item is not None else None
        if access is not None and self._interior_in_view(*access, joints, in_frame):
            extra["inside"] = access[0].category
        return {**label, **extra}

    def _interior_in_view(self, storage: Furniture, part_name: str, joints: dict[int, dict[str, float]],
                          in_frame: set[int]) -> bool:
        """Whether a frame with the ids ``in_frame`` shows the inside of ``storage`` behind
        ``part_name``: that part open now, and the carcass or the part in the frame."""
        assert self._facts is not None
        piece = self._built.storage[storage.instance_id]
        part_id = piece.placement.part_ids()[part_name]
        opened = self._facts.is_open(storage, part_name, joints=joints[storage.instance_id])
        return opened and bool(in_frame & {storage.instance_id, part_id})

    def contact(self) -> Label | None:
        """The label of what the robot body touches now (the deepest contact), ignoring floors."""
        touching = self._touching()
        return None if touching is None else touching[0]

    def _touching(self) -> tuple[Label, tuple[float, float]] | None:
        """The deepest contact of the base's cylinder: the label (a storage part's own) and its (x, y)
        on the obstacle, ignoring floors."""
        x, y, _ = self.base_pose
        lo, hi = (x - ROBOT_RADIUS, y - ROBOT_RADIUS, 0.0), (x + ROBOT_RADIUS, y + ROBOT_RADIUS, ROBOT_HEIGHT)
        deepest: tuple[float, tuple[int, int], tuple[float, float]] | None = None
        for body in {body for body, _ in p.getOverlappingObjects(lo, hi, physicsClientId=self.client) or ()}:
            if body in (self._robot, self._base) or body in self._floors:
                continue
            for point in p.getClosestPoints(self._base, body, 0.0, physicsClientId=self.client):
                if deepest is None or point[8] < deepest[0]:
                    deepest = (point[8], (body, point[4]), (float(point[6][0]), float(point[6][1])))
        if deepest is None:
            return None
        labels = self._built.labels
        return labels.get(deepest[1], labels[(deepest[1][0], -1)]), deepest[2]

    def _arm_touching(self) -> tuple[Label, tuple[float, float]] | None:
        """Like `_touching`, for the arm's links and what the hand carries (floors and the held thing
        aside): the deepest contact's label and (x, y)."""
        arm, held = self.arm, self.arm.grip
        ours: list[tuple[int, int]] = [(self._robot, link) for link in arm.link_names]
        if held is not None and not held.tied:
            ours.append((held.body, -1))
        deepest: tuple[float, tuple[int, int], tuple[float, float]] | None = None
        for body, link in ours:
            lo, hi = p.getAABB(body, link, physicsClientId=self.client)
            for other in {b for b, _ in p.getOverlappingObjects(lo, hi, physicsClientId=self.client) or ()}:
                if other in (self._robot, self._base, body) or other in self._floors or (held and other == held.body):
                    continue
                for point in p.getClosestPoints(body, other, 0.0, linkIndexA=link, physicsClientId=self.client):
                    if deepest is None or point[8] < deepest[0]:
                        deepest = (point[8], (other, point[4]), (float(point[6][0]), float(point[6][1])))
        if deepest is None:
            return None
        return self._label_of(*deepest[1]), deepest[2]

    def move_base(self, path: list[tuple[float, float]], yaw: float | None = None) -> MoveResult:
        """Follow the polyline in steps of at most `MAX_STEP`, then turn; stop before any contact.

        A stowed arm lies inside the base's cylinder, so only the base is checked; an arm that is
        out, or holds something, is checked too, and what it carries goes along. A grasped handle
        ties the robot to its furniture: the base does not move until the gripper opens.
        """
        held = self.arm.grip
        if held is not None and held.tied:
            raise ValueError(f"move_base: the gripper holds {self._label_of(held.body, held.link)['category']} "
                             f"{self._label_of(held.body, held.link)['id']}; open it first")
        arm_out = held is not None or not self.arm.is_stowed()
        x, y, heading = self.base_pose
        travelled = 0.0
        for tx, ty in path:
            length = math.hypot(tx - x, ty - y)
            steps = math.ceil(length / MAX_STEP)
            for k in range(1, steps + 1):
                nx, ny = x + (tx - x) * k / steps, y + (ty - y) * k / steps
                hit = self._step_to((nx, ny, heading), arm_out)
                if hit is not None:
                    previous = k - 1
                    self._step_to((x + (tx - x) * previous / steps, y + (ty - y) * previous / steps, heading), False)
                    return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
                travelled += length / steps
            x, y = tx, ty
        if yaw is not None:
            hit = self._step_to((x, y, yaw), arm_out)
            if hit is not None:
                self._step_to((x, y, heading), False)
                return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
        return MoveResult(self.base_pose, True, None, travelled)

    def _step_to(self, pose: Pose, arm_out: bool) -> tuple[Label, tuple[float, float]] | None:
        """Teleport the robot (and what it carries) to ``pose``; what it touches there, if anything."""
        self.place(pose)
        self.arm.carry()
        hit = self._touching()
        if hit is None and arm_out:
            hit = self._arm_touching()
        return hit

    # -- the arm ---------------------------------------------------------------------------------

    def _label_of(self, body: int, link: int) -> Label:
        """The label of a body's link, with ``link`` naming a storage piece's part or handle (else None)."""
        labels = self._built.labels
        label = labels.get((body, link), labels[(body, -1)])
        name = None
        for piece in self._built.storage.values():
            if piece.body == body:
                name = next((n for n, index in piece.links.items() if index == link), None)
        return {**label, "link": name}

    def _held_label(self) -> Label | None:
        grip = self.arm.grip
        return None if grip is None else self._label_of(grip.body, grip.link)

    def arm_state(self) -> ArmState:
        arm = self.arm
        return ArmState(arm.positions(), arm.link_pose(arm.spec.tcp_frame), arm.gripper_width(), self._held_label(),
                        arm.is_stowed())

    def follow_trajectory(self, samples: np.ndarray, dt: float, stop_on_contact: bool = False) -> TrajectoryResult:
        """Run the lift and arm through ``samples`` (N, 8: `arm_spec` order), one every ``dt`` seconds.

        ``samples`` must already lie within the joint limits (the command parser checks that); here
        the first sample must start where the arm is, within one sample's travel at full speed plus
        `START_TOLERANCE`. Contacts of the arm with anything but floors, the held thing and the part
        whose handle is held are reported, and with ``stop_on_contact`` end the motion early.
        """
        arm = self.arm
        samples = np.asarray(samples, dtype=float)
        reach = arm.spec.column("velocity") * dt + START_TOLERANCE
        gap = np.abs(samples[0] - arm.positions())
        if np.any(gap > reach):
            k = int(np.argmax(gap - reach))
            raise ValueError(f"samples[0][{k}]: {samples[0][k]:.4f} is {gap[k]:.4f} from where {arm.spec.names[k]} "
                             f"is ({arm.positions()[k]:.4f}); a trajectory starts where the arm is")
        grip = arm.grip
        held = set() if grip is None else {(grip.body, link) for link in grip.links}
        run = arm.follow(samples, dt, self.riders.sync, stop_on_contact,
                         lambda body, link: (body, link) in held or body in self._floors)
        contacts = [{**self._label_of(t.body, t.link), "robot_link": t.robot_link, "depth": t.depth}
                    for t in run.touches]
        return TrajectoryResult(run, contacts)

    def gripper(self, close: bool) -> Label | None:
        """Close the gripper (grasping what the fingers meet) or open it (letting go); what it holds after.

        Closing grasps what both fingers touch when they stop: an object, or a storage piece's part
        or handle (the deepest touch first); walls, floors, tables and carcasses are not graspable.
        Opening puts a carried object down straight onto whatever is under it.
        """
        arm = self.arm
        if close:
            if arm.grip is None:
                arm.move_fingers(0.0, self.riders.sync)
                target = self._graspable(arm.touched_by_gripper())
                if target is not None:
                    body, link = target
                    tied = link >= 0
                    if not tied:
                        self.riders.lift(self._item_of(body))
                    arm.hold(body, link, tied)
            return self._held_label()
        grip = arm.let_go()
        if grip is not None and not grip.tied:
            self._put_down(grip.body)
        arm.move_fingers(arm.spec.finger_travel, self.riders.sync)
        return None

    def _item_of(self, body: int) -> int:
        return next(item for item, b in self._built.items.items() if b == body)

    def _graspable(self, touches: list[Touch]) -> tuple[int, int] | None:
        """(body, link) to grasp: an object (link -1) or a storage part or handle that both fingers
        touch, the deepest touched first."""
        items = set(self._built.items.values())
        storage = {piece.body for piece in self._built.storage.values()}
        fingers = {self.arm.link_names[f] for f in self.arm.fingers}
        touched_by: dict[tuple[int, int], set[str]] = {}
        depth: dict[tuple[int, int], float] = {}
        for touch in touches:
            if touch.body in items:
                key = (touch.body, -1)
            elif touch.body in storage and touch.link >= 0:
                key = (touch.body, touch.link)
            else:
                continue
            touched_by.setdefault(key, set()).add(touch.robot_link)
            depth[key] = min(depth.get(key, math.inf), touch.depth)
        pinched = [key for key, links in touched_by.items() if fingers <= links]
        return min(pinched, key=depth.__getitem__, default=None)

    def _put_down(self, body: int) -> None:
        """Let a carried object down straight onto the highest thing under its footprint (the floor
        level when nothing is), and make it ride on that thing."""
        lo, hi = p.getAABB(body, -1, physicsClientId=self.client)
        position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
        p.resetBasePositionAndOrientation(body, _OUT_OF_SIGHT, orientation, physicsClientId=self.client)
        robot = self.base_pose
        self._hide_robot()
        try:
            xs = (*np.linspace(lo[0], hi[0], 4)[1:-1], (lo[0] + hi[0]) / 2)  # a 3 x 3 grid inside the footprint
            ys = (*np.linspace(lo[1], hi[1], 4)[1:-1], (lo[1] + hi[1]) / 2)
            starts = [(float(x), float(y), lo[2] + 0.02) for x in xs for y in ys]
            hits = p.rayTestBatch(starts, [(x, y, lo[2] - 3.0) for x, y, _ in starts], physicsClientId=self.client)
        finally:
            self.place(robot)
        found = [(hit[3][2], (hit[0], hit[1])) for hit in hits if hit[0] >= 0]
        top, support = max(found, default=(0.0, None))
        dropped = (position[0], position[1], position[2] + top - lo[2])
        p.resetBasePositionAndOrientation(body, dropped, orientation, physicsClientId=self.client)
        self.riders.put(self._item_of(body), support)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)
