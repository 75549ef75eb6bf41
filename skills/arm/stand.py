"""Where the base stands to open a door or drawer that stands on the floor: clear of what the
opening sweeps, with the handle's whole path within the arm's reach.

A door swings towards whoever pulls it. Stood square in front of it and near, the robot is struck
by its own hand (which rides the handle round the hinge towards the base) or by the door's free
edge, and the door stops halfway; too far, and the handle is out of reach. The candidates
(`candidate_poses`) face the front square on, each a distance out from the handle along the
front's normal and, for a door on a vertical hinge, a share of the way from the handle towards the
hinge (`StandConfig`). For the widest opening first, then narrower ones (a door at 60° still shows
most of its shelves), the nearest candidate is taken where

- the base may stand and arrive (``reachable``, e.g. a path over the robot's map);
- the hand on the handle and, for a door, its front from hinge to free edge keep
  `StandConfig.margin_m` clear of the base's body (``planner.body_radius``) all the way open
  (`swept_clearance`, from the geometry alone);
- the opening plans (`ArmPlanner.plan_open`: IK along the whole path) and the planned hand keeps
  as clear (`hand_clearance`: the grasp variant planned may tilt the hand).

Planning costs a second or two, so at most `StandConfig.max_plans` plans are tried. Pure: no bus,
no world.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from agent.perception.grasp_poses import grasp_pose
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import part_motion
from agent.pose import Pose2D
from skills.arm.frames import base_transform
from skills.arm.grasps import hand_corners
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlan, SkillPlanError

#: Steps along an opening at which the swept front is checked against the base.
SWEEP_SAMPLES = 12


@dataclass(frozen=True)
class StandConfig:
    """Where the base may stand to open a part, and how hard to look for such a place.

    Every (hinge share, distance) pair is a candidate; the nearest clear one is taken.

    Args:
        distances_m: how far out from the handle (along the front's normal) the base may stand.
        hinge_shares: for doors on a vertical hinge, how far from the handle towards the hinge, as
            a share of the handle's distance from it (0 is level with the handle; towards the
            hinge the door's free edge swings past the body sooner).
        door_amounts: door openings to plan for, widest first (rad).
        drawer_amounts: drawer openings to plan for, widest first (m).
        margin_m: room kept between the base's body and the hand or the moving front.
        max_plans: arm plans tried at most before giving up.

    Raises:
        ValueError: an empty or out-of-range setting.
    """

    distances_m: tuple[float, ...] = (1.0, 0.9, 0.8, 1.1)
    hinge_shares: tuple[float, ...] = (0.3, 0.6, 0.0)
    door_amounts: tuple[float, ...] = (math.radians(75.0), math.radians(60.0), math.radians(45.0))
    drawer_amounts: tuple[float, ...] = (0.2, 0.15)
    margin_m: float = 0.04
    max_plans: int = 8

    def __post_init__(self) -> None:
        for name in ("distances_m", "door_amounts", "drawer_amounts"):
            values = getattr(self, name)
            if not values or not all(v > 0 for v in values):
                raise ValueError(f"act.stand.{name}: {values!r} must be one or more positive numbers")
        if not self.hinge_shares or not all(0.0 <= s <= 1.0 for s in self.hinge_shares):
            raise ValueError(f"act.stand.hinge_shares: {self.hinge_shares!r} must be one or more shares in [0, 1]")
        if self.margin_m < 0 or self.max_plans < 1:
            raise ValueError("act.stand.margin_m must be ≥ 0 and act.stand.max_plans ≥ 1")


class NoStandError(SkillPlanError):
    """No candidate stand would do; ``refused`` and ``why`` let the caller try elsewhere or say why.

    Args:
        kind: the part's kind ("door", "drawer").
        refused: the candidates turned down, counted by why (those in the way or out of reach
            once for each opening tried).
        plans: arm plans tried.
        max_plans: the most that were allowed.
    """

    def __init__(self, kind: str, refused: Counter[str], plans: int, max_plans: int) -> None:
        self.refused = refused
        reasons = ", ".join(f"{count} {reason}" for reason, count in refused.items() if count)
        self.why = f"{reasons}; {plans} of at most {max_plans} plans tried"
        super().__init__(f"stand: no place to open the {kind} from ({self.why})")


@dataclass(frozen=True)
class Stand:
    """Where to open a part from.

    Args:
        pose: the base pose.
        amount: how far to open the part from there (rad or m).
        clearance_m: the least distance the hand and the moving front keep from the base's axis
            over that opening.
    """

    pose: Pose2D
    amount: float
    clearance_m: float


def choose_stand(planner: ArmPlanner, q: np.ndarray, geometry: PartGeometry, *,
                 reachable: Callable[[np.ndarray], bool] | None = None, surface_z: float | None = None,
                 config: StandConfig = StandConfig()) -> Stand:
    """The nearest candidate stand (see the module doc) from which a part opens by the widest of
    the config's amounts.

    Args:
        planner: the arm's planner.
        q: where the arm is (it starts every plan).
        geometry: the part as seen closed.
        reachable: whether the base may stand and arrive at an (x, y) (None: everywhere).
        surface_z: the top of what the part stands on, which the hand keeps above.
        config: the candidates and limits.

    Returns:
        The stand, the opening planned from it and its clearance.

    Raises:
        NoStandError: saying how many candidates failed on each count.
    """
    needed = planner.body_radius + config.margin_m
    handle = np.asarray(geometry.handle_point[:2], dtype=float)
    poses = [pose for pose in candidate_poses(geometry, config)
             if reachable is None or reachable(np.array(pose[:2]))]
    refused = Counter({"unreachable": len(candidate_poses(geometry, config)) - len(poses)})
    plans = 0
    for amount in config.door_amounts if geometry.kind == "door" else config.drawer_amounts:
        clear = []
        for pose in poses:
            swept = swept_clearance(geometry, amount, np.array(pose[:2]))
            if swept >= needed:
                clear.append((math.dist(pose[:2], handle), pose, swept))
            else:
                refused["in the way of the opening"] += 1
        for _, pose, swept in sorted(clear):
            if plans >= config.max_plans:
                break
            plans += 1
            try:
                plan = planner.plan_open(q, pose, geometry, amount, surface_z=surface_z)
            except SkillPlanError:
                refused["out of the arm's reach"] += 1
                continue
            hand = hand_clearance(planner, plan)
            if hand < needed:
                refused["struck by the hand"] += 1
                continue
            return Stand(pose, amount, min(swept, hand))
    raise NoStandError(geometry.kind, refused, plans, config.max_plans)


def candidate_poses(geometry: PartGeometry, config: StandConfig = StandConfig()) -> list[Pose2D]:
    """Base poses facing a part's front square on, nearest the handle or towards a door's hinge.

    Args:
        geometry: the part as seen closed.
        config: the distances and hinge shares.

    Returns:
        A pose for every (hinge share, distance) pair of the config; drawers and doors on a
        horizontal hinge (flaps) are stood before level with the handle (share 0 only).

    Raises:
        SkillPlanError: the part's front normal is vertical.
    """
    normal = _horizontal(geometry.normal, "the part's front normal")
    yaw = math.atan2(-normal[1], -normal[0])
    handle = np.asarray(geometry.handle_point[:2], dtype=float)
    toward_hinge = np.zeros(2)
    shares: Sequence[float] = (0.0,)
    if geometry.kind == "door" and geometry.hinge_point is not None and abs(float(geometry.hinge_axis[2])) > 0.7:
        offset = np.asarray(geometry.hinge_point[:2], dtype=float) - handle
        toward_hinge = offset - (offset @ normal) * normal
        shares = config.hinge_shares
    poses = []
    for share in shares:
        for distance in config.distances_m:
            x, y = handle + share * toward_hinge + distance * normal
            poses.append(Pose2D(float(x), float(y), yaw))
    return poses


def swept_clearance(geometry: PartGeometry, amount: float, base_xy: np.ndarray) -> float:
    """How close what moves while a part opens comes to the base, from the geometry alone.

    Args:
        geometry: the part as seen closed.
        amount: how far it opens (rad or m).
        base_xy: the base's axis (world x, y).

    Returns:
        The least horizontal distance from ``base_xy`` to the hand on the handle (at its plain
        grasp, `grasp_pose`) and, for a door, its front from the hinge line to the free edge
        (`PartGeometry.swing_radius`) at the handle's height (m).
    """
    base = np.asarray(base_xy, dtype=float)[:2]
    grasp = grasp_pose(geometry)
    front = np.zeros((0, 3))
    if geometry.kind == "door":
        assert geometry.hinge_point is not None and geometry.hinge_axis is not None
        spoke = geometry.handle_point - geometry.hinge_point
        spoke = spoke - (spoke @ geometry.hinge_axis) * geometry.hinge_axis
        spoke /= np.linalg.norm(spoke)
        front = geometry.hinge_point + np.outer(np.linspace(0.0, geometry.swing_radius, 8), spoke)
    least = math.inf
    for value in np.linspace(0.0, amount, SWEEP_SAMPLES):
        motion = part_motion(geometry, float(value))
        moved = np.vstack([front @ motion[:3, :3].T + motion[:3, 3], hand_corners(motion @ grasp)])
        least = min(least, float(np.hypot(*(moved[:, :2] - base).T).min()))
    return least


def hand_clearance(planner: ArmPlanner, plan: SkillPlan) -> float:
    """How close the planned hand comes to the base while it carries the part (the grasp variant
    planned may tilt the hand).

    Args:
        planner: the arm's planner.
        plan: an opening's plan.

    Returns:
        The least horizontal distance from the base's axis to the hand and open fingers over the
        plan's moves that carry a part (m).
    """
    base = base_transform(plan.base_pose)
    least = math.inf
    for step in plan.steps:
        if step.part_motion is None or step.samples is None:
            continue
        for q in step.samples:
            tcp = base @ planner.kin.forward(q)
            corners = hand_corners(tcp)
            least = min(least, float(np.hypot(corners[:, 0] - base[0, 3], corners[:, 1] - base[1, 3]).min()))
    return least


def _horizontal(vector: np.ndarray, what: str) -> np.ndarray:
    flat = np.array([vector[0], vector[1]], dtype=float)
    if np.linalg.norm(flat) < 1e-6:
        raise SkillPlanError(f"stand: {what} is vertical")
    return flat / np.linalg.norm(flat)


def stand_pose(geometry: PartGeometry, base_pose: Pose2D,
               door_share: float = 0.35, distance_m: float | None = None) -> Pose2D:
    """Where the base should stand to open or close a part, from where it stands now.

    It stays as far from the part's front as it is (slid along the front, never towards it), or
    ``distance_m`` from the handle along the front's normal when given, and turns to face the front
    square on, with its axis opposite the handle of a drawer, or ``door_share`` of the way from a
    door's hinge to its handle: there the door, swinging open, passes beside the arm instead of
    through it, and the handle stays within reach.

    Args:
        geometry: the part.
        base_pose: where the base stands now.
        door_share: how far from a door's hinge towards its handle the base's axis aims.
        distance_m: the distance from the handle along the front's normal (None: as far as now).

    Returns:
        The base pose.

    Raises:
        SkillPlanError: the part's front normal is vertical.
    """
    x, y, _ = (float(v) for v in base_pose)
    normal = np.array([geometry.normal[0], geometry.normal[1]], dtype=float)
    if np.linalg.norm(normal) < 1e-6:
        raise SkillPlanError("stand pose: the part's front normal is vertical")
    normal /= np.linalg.norm(normal)
    along = np.array([-normal[1], normal[0]])
    if geometry.kind == "door" and geometry.hinge_point is not None:
        aim = geometry.hinge_point[:2] + door_share * (geometry.handle_point[:2] - geometry.hinge_point[:2])
    else:
        aim = geometry.handle_point[:2]
    here = np.array([x, y])
    there = here + along * float((aim - here) @ along)
    if distance_m is not None:
        there = aim + normal * float(distance_m)
    return Pose2D(float(there[0]), float(there[1]), math.atan2(-normal[1], -normal[0]))
