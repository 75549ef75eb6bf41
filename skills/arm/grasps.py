"""The hand's shape, and the grasps that hold a thing by resting the closed fingertips on it.

The world holds whatever the closed fingers touch (`worlds.sim.World.gripper`): a handle is tied
to the hand, an object carried with it. A thing need not fit between the fingers to be held, then:
with the fingers closed first, their tips brought onto it until they touch, closing again holds
it. Three grasps do that where the usual one (the fingers open around a bar or an
object, closing across it) cannot:

- a level bar from above (`handle_top_grasps`). The usual grasp of a bar (`level_grasps`) closes
  with one finger above it and one below, so the hand, 21 cm across its fingers' travel, reaches
  10.6 cm below the bar (`HAND_BOXES`): into the table under a drawer whose handle is less than
  ~9 cm over it. From above, the fingers' span lies along the bar and the hand points down at it,
  pitched towards the front (`TOP_PITCHES`) so that it leans out, away from the front and from
  the handles of the drawers above (at 30° or more, all of the hand 9.5 cm above the bar stands
  4 cm or more further out than the bar's centre). The drawer is then pulled along its line as the
  level grasp pulls it;
- an object's top (`object_grasps`): an object wider than the opening (an open-bottom box, a jar,
  a bottle) is held by the closed fingertips on its top (a box's lid), the fingers closing along
  the directions the usual grasp would, best first; then, for a box whose middle is out of reach
  (a wide box at the table's far side: the hand above its middle fell 15 cm short), on the top
  just inside its near edge (`EDGE_INSET_M`), straight down and leaning back towards the robot
  (`EDGE_PITCHES`). The world carries what the fingers hold as it was held, so a box held by its
  edge is lifted straight up like one held by its middle;
- an object's side (`side_grasps`): the hand level, the closed fingertips against the middle of
  the side that faces the robot, low on it. Under a board close over a box in a cabinet no hand
  on its top has room for the wrist above it; one at its side needs room only to lift it clear of
  what it covers, and for the wrist's links beside the hand.

All are *touch* grasps: perception places a top or a side to within half a voxel, and a hand
closing on a surface must meet it, so the approach goes on past where the surface is expected
(`TOUCH_SEARCH_M`) and ends on the first touch (`skills.arm.skill_plan.Step.touch`); what follows
is planned from where the surface was expected, and re-timed from where the arm stopped. Letting go of a bar so held, the
fingertips lift straight off it (`LIFT_OFF_M`) before the hand backs off along its pitched axis,
which would drag the bar out with them.

Hand geometry for clearance checks: `hand_corners`, `hand_bottom` (what must stay above a table),
`front_clearance` (how far the hand stays in front of a part's front) and `hand_touches` (what
standing beside the thing grasped the hand would touch).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from agent.perception.grasp_poses import grasp_pose
from agent.perception.part_geometry import PartGeometry
from agent.pose import Pose2D

UP = np.array([0.0, 0.0, 1.0])
#: The hand's and open fingers' boxes in the TCP frame (lo, hi corners; from the Panda's collision
#: meshes): what must stay above a surface (``surface_z``) while the hand works at a handle.
HAND_BOXES = (((-0.034, -0.106, -0.131), (0.034, 0.106, -0.035)),
              ((-0.012, -0.068, -0.045), (0.012, 0.068, 0.011)))
#: How far (m) beyond its boxes the hand counts as touching a point: the memory's voxel.
HAND_MARGIN_M = 0.01
#: How far the fingertips reach past the TCP along its axis: the Panda's finger collision mesh is
#: 53.8 mm long from its joint, 58.4 mm down the hand; the TCP is 103.4 mm down the hand.
FINGERTIP_M = 0.009
#: How much deeper (m) a thing may be along the line of sight than the memory has it: a voxel, its
#: far side hidden from the cameras on the robot.
HIDDEN_DEPTH_M = 0.01
#: Where a level bar's top is expected above the centre of its points: half a 1.6 cm bar. Only
#: where the approach is aimed; the touch finds the top.
HANDLE_TOP_M = 0.008
#: How far a touch grasp's approach goes on past where the top is expected.
TOUCH_SEARCH_M = 0.02
#: How far fingertips that held a bar from above lift straight up off it before backing off.
LIFT_OFF_M = 0.02
#: Pitches (rad from straight down, towards the front) of grasps on a level bar from above, best first.
TOP_PITCHES = tuple(math.radians(degrees) for degrees in (40.0, 30.0, 50.0))
#: A level bar: its axis within this (sine) of horizontal.
LEVEL_SIN = 0.1
#: How far past the perceived handle point (along the approach) the TCP closes in a level grasp:
#: the centre of a bar's voxels lies within a few millimetres of its axis when its face and top
#: are both seen.
HANDLE_DEPTH_M = 0.0
#: How far inside a top's near edge (m) fingertips rest when its middle is out of reach.
EDGE_INSET_M = 0.03
#: The same in the open, where no board limits how far in the hand leans: at its idle spot the
#: memory had a box's near side 1.5 cm nearer the robot than it stood, and fingertips meant to rest
#: 3 cm inside it came down at its very edge and held nothing (recursive 1182 of tuning-wide).
OPEN_EDGE_INSET_M = 0.06
#: How far (rad from straight down) the hand on a top's near edge leans back towards the robot, in
#: the order tried: the wrist then stands nearer the base than the fingertips, and at the steepest,
#: under a board close over the top, out of the storage it reached into.
EDGE_PITCHES = tuple(math.radians(degrees) for degrees in (0.0, 30.0, 50.0, 65.0))
#: How high over an object's bottom (m) the TCP of a hand at its side stands: the hand, 6.8 cm
#: thick across its fingers' plane (`HAND_BOXES`), a centimetre clear of the floor under it.
SIDE_TCP_HEIGHT_M = 0.08
#: An object's side is held only where the fingertips meet it this far (m) under its top or more.
SIDE_BELOW_TOP_M = 0.01
#: Level grasp variants tried in order: half turns about the gripper's axis, tilts about the
#: handle's bar (negative: the gripper points down onto a level bar, the hand above it; `tilted`).
FLIPS = (0.0, math.pi)
TILTS = (0.0, -0.3, 0.3, -0.15, 0.15)


@dataclass(frozen=True, eq=False)
class HandleGrasp:
    """One way of holding a handle, tried in turn until one reaches along the part's whole path.

    Args:
        offset: the TCP's 4×4 pose relative to the part's `grasp_pose`, so that the grasp rides
            along the part's path.
        name: what plans and reasons call it ("level", "from above").
        touch: the fingers close before the approach, which ends on touching the handle.
    """

    offset: np.ndarray
    name: str
    touch: bool = False


@dataclass(frozen=True, eq=False)
class ObjectGrasp:
    """A top-down grasp at an object's grasp point (the middle of its top).

    Args:
        rotation: the TCP's 3×3 rotation.
        depth: how far below the grasp point the TCP closes (negative: above it, the fingertips on the top).
        name: as plans say it ("fingers-around", "fingertips-on-top", "fingertips-on-near-edge",
            "fingertips-on-near-side").
        touch: as for `HandleGrasp`.
        offset: where on the top the grasp is, from its middle (world, horizontal); the thing is
            carried by that point, so its release point shifts by as much.
    """

    rotation: np.ndarray
    depth: float
    name: str
    touch: bool = False
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))


_HAND_CORNERS = np.array([[x, y, z] for lo, hi in HAND_BOXES
                          for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def hand_corners(tcp_pose: np.ndarray) -> np.ndarray:
    """Where the hand and open fingers are, for clearance checks.

    Args:
        tcp_pose: the TCP's 4×4 pose (world frame).

    Returns:
        The (16, 3) corners of the hand's and open fingers' boxes (`HAND_BOXES`).
    """
    return _HAND_CORNERS @ tcp_pose[:3, :3].T + tcp_pose[:3, 3]


def hand_touches(tcp_pose: np.ndarray, points: np.ndarray | None, margin_m: float = HAND_MARGIN_M) -> int:
    """How many of ``points`` the hand and open fingers would touch at a pose, for preferring grasps
    clear of what stands beside the thing grasped.

    Args:
        tcp_pose: the TCP's 4×4 pose (world frame).
        points: (N, 3) points of what the hand is to keep off (world), or None.
        margin_m: how far beyond the hand's boxes (`HAND_BOXES`) a point still counts.

    Returns:
        The points within ``margin_m`` of any of the boxes.
    """
    if points is None or not len(points):
        return 0
    local = (np.asarray(points, dtype=float) - tcp_pose[:3, 3]) @ tcp_pose[:3, :3]
    inside = np.zeros(len(local), dtype=bool)
    for lo, hi in HAND_BOXES:
        inside |= np.all((local >= np.subtract(lo, margin_m)) & (local <= np.add(hi, margin_m)), axis=1)
    return int(inside.sum())


def hand_bottom(tcp_pose: np.ndarray, base: np.ndarray | None = None, body_radius: float = 0.0) -> float:
    """How low the hand comes, to keep it above a table.

    Args:
        tcp_pose: the TCP's 4×4 pose (world frame).
        base: the base's 4×4 world pose; with it only the corners further than ``body_radius``
            from its axis count: over the robot's own body there is no table (the stowed arm sits
            inside it).
        body_radius: the base's body around its axis (m).

    Returns:
        The lowest world z of the hand's and open fingers' boxes (`HAND_BOXES`); inf when no corner counts.
    """
    corners = hand_corners(tcp_pose)
    if base is not None:
        corners = corners[np.hypot(corners[:, 0] - base[0, 3], corners[:, 1] - base[1, 3]) > body_radius]
    return float(corners[:, 2].min()) if len(corners) else math.inf


def front_clearance(tcp_pose: np.ndarray, geometry: PartGeometry) -> float:
    """How far the hand keeps in front of a part's front face, for grasps of its handle from above.

    Args:
        tcp_pose: the TCP's 4×4 pose (world frame).
        geometry: the part, with its front's depth behind the handle.

    Returns:
        The distance of the hand's (`HAND_BOXES`) nearest corner in front of the front (negative:
        through it); -inf when the front's depth is unknown.
    """
    if geometry.front_depth is None:
        return -math.inf
    ahead = (hand_corners(tcp_pose) - geometry.handle_point) @ geometry.normal
    return float(ahead.min() + geometry.front_depth)


def _rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def local_pose(rotation: np.ndarray | None = None, z: float = 0.0) -> np.ndarray:
    """A transform in the TCP's own frame, to back off along the gripper's axis or turn a grasp.

    Args:
        rotation: a 3×3 rotation (None: none).
        z: the shift along the (rotated) z axis (m).

    Returns:
        The 4×4 transform: the rotation, then the shift along its new z.
    """
    pose = np.eye(4)
    if rotation is not None:
        pose[:3, :3] = rotation
    pose[:3, 3] = pose[:3, :3] @ [0.0, 0.0, z]
    return pose


def tilted(grasp: np.ndarray, flip: float, tilt: float) -> np.ndarray:
    """A level grasp variant, turned about the gripper's axis and tilted about the bar.

    Args:
        grasp: the part's 4×4 `grasp_pose`.
        flip: the turn about the gripper's axis (rad).
        tilt: the tilt about the bar (rad), signed so that a negative one points the gripper down
            (a level bar grasped from above).

    Returns:
        The 4×4 offset of the variant relative to ``grasp``.
    """
    turned = _rotation_z(flip)
    rotation = turned @ _rotation_x(tilt)
    pointing = (grasp[:3, :3] @ rotation)[2, 2]  # the tilted approach's vertical component
    if tilt and (pointing > 0) == (tilt < 0) and abs(pointing) > 1e-6:
        rotation = turned @ _rotation_x(-tilt)
    return local_pose(rotation)


def level_grasps(closed: np.ndarray) -> list[HandleGrasp]:
    """The usual grasps of a handle: the fingers open across the bar, the hand square to the front.

    Args:
        closed: the handle's 4×4 `grasp_pose` with the part closed.

    Returns:
        The variants turned by `FLIPS` and tilted about the bar by `TILTS`, in the order to try them.
    """
    return [HandleGrasp(tilted(closed, flip, tilt) @ local_pose(z=HANDLE_DEPTH_M), "level") for flip in FLIPS
            for tilt in TILTS]


def top_rotation(closing: np.ndarray, pitch: float = 0.0, into: np.ndarray | None = None) -> np.ndarray:
    """The TCP's rotation for a grasp from above.

    Args:
        closing: the horizontal direction the fingers close along.
        pitch: how far the approach turns from straight down (rad) towards ``into``.
        into: the horizontal direction to pitch towards (None: straight down).

    Returns:
        The 3×3 rotation, columns x, y = ``closing``, z = the approach.
    """
    y = np.asarray(closing, dtype=float) / np.linalg.norm(closing)
    z = -math.cos(pitch) * UP
    if into is not None:
        z = z + math.sin(pitch) * np.asarray(into, dtype=float)
    return np.column_stack([np.cross(y, z), y, z])


def fingertips_on(rotation: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Where the TCP is when the closed fingertips rest on a point.

    Args:
        rotation: the TCP's 3×3 rotation.
        point: where the fingertips' ends meet (world).

    Returns:
        The TCP's 4×4 pose.
    """
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = np.asarray(point, dtype=float) - FINGERTIP_M * rotation[:, 2]
    return pose


def handle_top_grasps(geometry: PartGeometry) -> list[HandleGrasp]:
    """Grasps of a drawer's level bar from above (see the module docstring).

    Args:
        geometry: the part as seen closed.

    Returns:
        Every pitch of `TOP_PITCHES`, each with the hand either way round along the bar, in the
        order to try them; none for doors (the bar turns with the door) or a bar that is not level.
    """
    axis = np.asarray(geometry.handle_axis, dtype=float)
    if geometry.kind != "drawer" or abs(axis[2]) > LEVEL_SIN:
        return []
    to_closed = np.linalg.inv(grasp_pose(geometry))
    top = geometry.handle_point + HANDLE_TOP_M * UP
    into = -np.asarray(geometry.normal, dtype=float)
    return [HandleGrasp(to_closed @ fingertips_on(top_rotation(sign * axis, pitch, into), top),
                        "from above", touch=True)
            for pitch in TOP_PITCHES for sign in (1.0, -1.0)]


def closing_directions(size: np.ndarray, point: np.ndarray, base_pose: Pose2D) -> list[np.ndarray]:
    """Horizontal directions for the fingers to close along (the TCP's y) on an object, best first.

    First across the line of sight from the base: a camera on the robot places a thing best across
    that line and worst along it (it sees only its near side), and fingers closing across the line
    of sight forgive an error along it. Then the box's narrower axis, the other, the diagonals.

    Args:
        size: the object's box (dx, dy, dz).
        point: its grasp point (world).
        base_pose: where the base stands.

    Returns:
        Unit 3-vectors, each followed by its opposite (the hand turned half a turn).
    """
    sight = np.asarray(point[:2], dtype=float) - np.asarray(base_pose[:2], dtype=float)
    sight = sight / np.linalg.norm(sight) if np.linalg.norm(sight) > 1e-6 else np.array([1.0, 0.0])
    narrow, wide = ((1.0, 0.0), (0.0, 1.0)) if size[0] <= size[1] else ((0.0, 1.0), (1.0, 0.0))
    diagonal = math.sqrt(0.5)
    found: list[np.ndarray] = []
    for x, y in [(-sight[1], sight[0]), narrow, wide, (diagonal, diagonal), (diagonal, -diagonal)]:
        for sign in (1.0, -1.0):
            direction = np.array([sign * x, sign * y, 0.0])
            if all(np.linalg.norm(direction - other) > 1e-6 for other in found):
                found.append(direction)
    return found


def across(size: np.ndarray, direction: np.ndarray) -> float:
    """How wide a box is along a horizontal direction, to tell whether it fits between the fingers.

    Args:
        size: the box (dx, dy, dz).
        direction: a horizontal unit vector.

    Returns:
        The box's width along it (m).
    """
    return float(abs(direction[0]) * size[0] + abs(direction[1]) * size[1])


def object_grasps(size: np.ndarray, point: np.ndarray, base_pose: Pose2D, opening: float,
                  depth: float, edge_inset_m: float = EDGE_INSET_M) -> list[ObjectGrasp]:
    """Top-down grasps of an object, best first.

    Args:
        size: the object's box (dx, dy, dz).
        point: its grasp point (world, the middle of its top).
        base_pose: where the base stands.
        opening: the widest the object may be across the fingers to close around it (m).
        depth: how far below the point the fingers close around it (m).
        edge_inset_m: how far inside the near edge the fingertips rest on it.

    Returns:
        The fingers around it along each of `closing_directions` it fits within ``opening`` (a
        voxel, `HIDDEN_DEPTH_M`, added along the line of sight);
        where it fits along none, the closed fingertips on its top along each, then on its top
        just inside the edge nearest the base (straight down, then leaning back by `EDGE_PITCHES`),
        the fingers closing across the line of sight, where that edge lies 1 cm or more from the middle.
    """
    directions = closing_directions(size, point, base_pose)
    sight = np.array([*(np.asarray(point[:2], dtype=float) - np.asarray(base_pose[:2], dtype=float)), 0.0])
    sight = sight / np.linalg.norm(sight) if np.linalg.norm(sight) > 1e-6 else sight
    # Along the line of sight the memory may fall a voxel short (the far side hidden): a 7 cm
    # shampoo bottle remembered 6 cm deep, closed around along it, met the bottle with a finger.
    around = [d for d in directions if across(size, d) + HIDDEN_DEPTH_M * abs(float(d @ sight)) <= opening]
    if around:
        return [ObjectGrasp(top_rotation(d), depth, "fingers-around") for d in around]
    grasps = [ObjectGrasp(top_rotation(d), -FINGERTIP_M, "fingertips-on-top", touch=True) for d in directions]
    if np.linalg.norm(sight) < 1e-6:
        return grasps
    out = _inside_towards(size, -sight, edge_inset_m)
    if out < 0.01:
        return grasps
    closing = np.array([-sight[1], sight[0], 0.0])
    return grasps + [ObjectGrasp(top_rotation(sign * closing, pitch, sight), -FINGERTIP_M, "fingertips-on-near-edge",
                                 touch=True, offset=-out * sight)
                     for pitch in EDGE_PITCHES for sign in (1.0, -1.0)]


def _inside_towards(size: np.ndarray, direction: np.ndarray, inset: float) -> float:
    """How far from the middle of a box's top (m) along a level unit ``direction`` a point stays
    ``inset`` inside every side: seen at a slant, the near edge of a box at its idle spot lay nearer
    along the line of sight than its width along that line, and fingertips meant 6 cm inside came
    down 2 cm inside it (recursive 1182 of tuning-wide)."""
    room = [(float(size[k]) / 2 - inset) / abs(float(direction[k])) for k in (0, 1) if abs(float(direction[k])) > 1e-9]
    return min(room) if room else 0.0


def side_grasps(size: np.ndarray, point: np.ndarray, base_pose: Pose2D) -> list[ObjectGrasp]:
    """Level grasps of an object's side facing the robot, by the closed fingertips against it.

    The side is the box's face (its boxes are level and square to the world) whose outward normal
    points most nearly at the base; the hand comes square onto it, so that both fingertips meet it
    together (the world holds what both fingers touch), its TCP `SIDE_TCP_HEIGHT_M` over the
    object's bottom, as low as keeps the hand off the floor under it.

    Args:
        size: the object's box (dx, dy, dz).
        point: its grasp point (world, the middle of its top).
        base_pose: where the base stands.

    Returns:
        Two grasps, the hand turned half round about its axis between them; none where the object
        is too low for the fingertips to meet its side (`SIDE_BELOW_TOP_M`) or stands at the base.
    """
    size = np.asarray(size, dtype=float)
    sight = np.asarray(point[:2], dtype=float) - np.asarray(base_pose[:2], dtype=float)
    if float(size[2]) < SIDE_TCP_HEIGHT_M + SIDE_BELOW_TOP_M or np.linalg.norm(sight) < 1e-6:
        return []
    axis = int(np.argmax(np.abs(sight)))
    into = np.zeros(3)
    into[axis] = math.copysign(1.0, float(sight[axis]))
    offset = -(float(size[axis]) / 2 + FINGERTIP_M) * into
    closing = np.array([-into[1], into[0], 0.0])
    depth = float(size[2]) - SIDE_TCP_HEIGHT_M
    return [ObjectGrasp(top_rotation(sign * closing, math.pi / 2, into), depth, "fingertips-on-near-side",
                        touch=True, offset=offset) for sign in (1.0, -1.0)]
