"""The whole arm kept clear of a table, of what stands near and of what the hand carries.

A plan's grasps check the hand and its fingers (`skills.arm.grasps.HAND_BOXES`) where they work;
the rest of the arm, from the shoulder to the wrist, moves wherever IK and joint-space moves take
it. Lowering a box close before the robot took the elbow down onto the table, which held the
arm back 13 cm short of where the box was to go; a free move into a cabinet swept the forearm
through the door standing open beside it and pushed it shut. `Clearance` says, for one posture,
what the links would touch: the links are spheres strung along the arm's skeleton, the origins
of successive revolute joints and the corners where a link turns between two of them
(`skills.arm.kinematics.ArmKinematics.skeleton`; `LINK_RADIUS_M` round: the Panda's links are
~12 cm thick), and where a link's mesh bulges out of that tube, spheres fixed to the link
(`skills.arm.link_shells`: the wrist's housing); the table is the surface the plan works over,
what stands near is the memory's points, and what the hand carries is a box fixed to the TCP. The
segment from the last joint to the TCP is the hand's, left to its boxes.

Pure: an `ArmModel`, the base's pose and points in, a reason or None out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from skills.arm.arm_model import ArmModel
from skills.arm.grasps import hand_touches
from skills.arm.link_shells import LINK_RADIUS_M

#: How far (m) the links keep above a surface, from other points and from what the hand carries.
CLEARANCE_M = 0.01
#: How far from the TCP (m) the hand and its open fingers reach at most.
HAND_REACH_M = 0.25
#: The bottom of what the hand carries that may touch what it stands on or is lifted off (m).
SUPPORT_M = 0.02
#: Points of what stands near within reach of a link that count as touching it: a voxel or two is
#: the memory's noise.
TOUCHING_POINTS = 3


def _outside(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """How far each point lies outside the box ``lo``..``hi`` (0 inside)."""
    return np.linalg.norm(np.maximum(np.maximum(lo - points, points - hi), 0.0), axis=1)


def box_points(centre: np.ndarray, extent: np.ndarray, step_m: float = 0.02) -> np.ndarray:
    """Points filling a world-aligned box, to stand for a thing known only by its box.

    Args:
        centre: the box's middle (world).
        extent: its size (dx, dy, dz).
        step_m: the most the points lie apart along each axis.

    Returns:
        (N, 3) points, the corners among them.
    """
    axes = [np.linspace(c - e / 2, c + e / 2, max(2, math.ceil(e / step_m) + 1)) for c, e in zip(centre, extent)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


@dataclass(frozen=True)
class Carried:
    """What the hand holds, as a box fixed to the TCP: its corners ``lo`` and ``hi`` relative to the
    TCP, along the world's axes as they were when it was grasped with the TCP turned ``rotation``
    (the box turns with the hand from there)."""

    lo: np.ndarray
    hi: np.ndarray
    rotation: np.ndarray

    @classmethod
    def held_at(cls, tcp_pose: np.ndarray, centre: np.ndarray, extent: np.ndarray) -> Carried:
        """The box of a thing standing upright with its middle at ``centre``, grasped with the TCP at
        ``tcp_pose``.

        Args:
            tcp_pose: the TCP's 4×4 world pose at the grasp.
            centre: the thing's middle (world).
            extent: its box (dx, dy, dz), world-aligned.

        Returns:
            The box, relative to the TCP.
        """
        half = np.asarray(extent, dtype=float) / 2
        offset = np.asarray(centre, dtype=float) - tcp_pose[:3, 3]
        return cls(offset - half, offset + half, tcp_pose[:3, :3].copy())

    def frame(self, tcp_pose: np.ndarray) -> np.ndarray:
        """The box's own 4×4 frame with the TCP at ``tcp_pose``: its axes the world's as grasped,
        turned as the hand has turned since, its origin at the TCP.

        Args:
            tcp_pose: the TCP's 4×4 world pose.

        Returns:
            The frame (world).
        """
        frame = np.eye(4)
        frame[:3, :3] = tcp_pose[:3, :3] @ self.rotation.T
        frame[:3, 3] = tcp_pose[:3, 3]
        return frame

    def world_corners(self, tcp_pose: np.ndarray) -> np.ndarray:
        """The box's eight corners with the TCP at ``tcp_pose``.

        Args:
            tcp_pose: the TCP's 4×4 world pose.

        Returns:
            (8, 3) world points.
        """
        corners = np.array([[x, y, z] for x in (self.lo[0], self.hi[0]) for y in (self.lo[1], self.hi[1])
                            for z in (self.lo[2], self.hi[2])])
        frame = self.frame(tcp_pose)
        return corners @ frame[:3, :3].T + frame[:3, 3]


class Clearance:
    """What one plan's arm must keep clear of, from a base standing at ``base``.

    Args:
        arm: the arm planned for.
        base: the base's 4×4 world pose.
        surface_z: the top of the surface the arm works over (world z), or None.
        obstacles: (N, 3) world points of what stands near, or None.
        radius_m: the links' radius.
        clearance_m: how far the links keep from all of it.
    """

    def __init__(self, arm: ArmModel, base: np.ndarray, surface_z: float | None = None,
                 obstacles: np.ndarray | None = None, radius_m: float = LINK_RADIUS_M,
                 clearance_m: float = CLEARANCE_M) -> None:
        self.arm = arm
        self.base = base
        self.surface_z = surface_z
        points = None if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 3)
        self.tree = cKDTree(points) if points is not None and len(points) else None
        self.radius = radius_m
        self.clearance = clearance_m

    def sphere_sets(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The links' sphere centres (world) for joint positions ``q``: along the skeleton, and where
        the links bulge out of the tube round it.

        Args:
            q: (dof,) joint positions.

        Returns:
            (M, 3) and (B, 3) centres.
        """
        arm = self.arm
        frames = self.base @ arm.kin.link_frames(q, arm.skeleton_first)
        tube, bulges = ([centres @ frame[:3, :3].T + frame[:3, 3] for frame, centres in zip(frames, local)]
                        for local in (arm.link_tubes, arm.link_bulges))
        return np.vstack([frames[0][None, :3, 3], *tube]), np.vstack([np.zeros((0, 3)), *bulges])

    def spheres(self, q: np.ndarray) -> np.ndarray:
        """All the links' sphere centres (world) for joint positions ``q`` (`sphere_sets`).

        Args:
            q: (dof,) joint positions.

        Returns:
            (M, 3) centres.
        """
        return np.vstack(self.sphere_sets(q))

    def problem(self, q: np.ndarray, carried: Carried | None = None, hand: bool = False,
                lifted: bool = False) -> str | None:
        """What the links would touch with the arm at ``q``, in words; None when nothing.

        Args:
            q: (dof,) joint positions.
            carried: what the hand holds, or None.
            hand: whether the hand and its open fingers count too (`skills.arm.grasps.HAND_BOXES`):
                on the way to a grasp, not at it.
            lifted: whether what the hand carries is lifted clear of what it stood on and of where
                it goes, so that its bottom (`SUPPORT_M`) counts too: a box carried out of a drawer
                with its bottom 1.5 cm under the top of the drawer's front went through it
                (recursive 1050 of tuning-wide).

        Returns:
            The reason, or None.
        """
        skeleton, bulges = self.sphere_sets(q)
        centres = np.vstack([skeleton, bulges])
        reach = self.radius + self.clearance
        if self.surface_z is not None:  # the skeleton's: the housings' undersides fold in low by the body
            off_body = np.hypot(*(skeleton[:, :2] - self.base[:2, 3]).T) > self.arm.body_radius
            low = float(skeleton[off_body, 2].min(initial=math.inf)) - self.radius
            if low < self.surface_z + self.clearance:
                return f"the arm's links would come down to {low:.3f} m, onto the surface at {self.surface_z:.3f} m"
        if self.tree is not None:
            touching = len(set().union(*self.tree.query_ball_point(centres, reach)))
            if touching >= TOUCHING_POINTS:
                return f"the arm's links would touch what stands near ({touching} points)"
        if hand and self.tree is not None:
            tcp = self.base @ self.arm.kin.forward(q)
            near = self.tree.query_ball_point(tcp[:3, 3], HAND_REACH_M)
            if near and hand_touches(tcp, self.tree.data[near], self.clearance) >= TOUCHING_POINTS:
                return "the hand would touch what stands near"
        if carried is not None:
            tcp = self.base @ self.arm.kin.forward(q)
            frame = carried.frame(tcp)
            local = (centres - frame[:3, 3]) @ frame[:3, :3]
            if float(_outside(local, carried.lo, carried.hi).min()) < reach:
                return "the arm's links would touch what the hand carries"
            if self.tree is not None:
                corners = carried.world_corners(tcp)
                lo, hi = corners.min(axis=0) - self.clearance, corners.max(axis=0) + self.clearance
                if not lifted:
                    lo[2] += self.clearance + SUPPORT_M  # what it stands on, or is lifted off
                middle, half = (lo + hi) / 2, (hi - lo) / 2
                near = self.tree.query_ball_point(middle, float(np.linalg.norm(half)))
                if near and int((_outside(self.tree.data[near], lo, hi) <= 0.0).sum()) >= TOUCHING_POINTS:
                    return "what the hand carries would touch what stands near"
        return None

    def carried_meets(self, q: np.ndarray, carried: Carried) -> bool:
        """Whether the thing the hand holds, with the arm at ``q``, would stand in what stands near:
        its own box, turned as it is held, with no margin (`problem` keeps `clearance` round the
        box squared to the world). What a route taken unchecked may not do.

        Args:
            q: (dof,) joint positions.
            carried: what the hand holds.

        Returns:
            Whether `TOUCHING_POINTS` or more of what stands near lie inside its box.
        """
        if self.tree is None:
            return False
        frame = carried.frame(self.base @ self.arm.kin.forward(q))
        middle = frame[:3, :3] @ ((carried.lo + carried.hi) / 2) + frame[:3, 3]
        near = self.tree.query_ball_point(middle, float(np.linalg.norm(carried.hi - carried.lo)) / 2)
        if not near:
            return False
        local = (self.tree.data[near] - frame[:3, 3]) @ frame[:3, :3]
        return int((_outside(local, carried.lo, carried.hi) <= 0.0).sum()) >= TOUCHING_POINTS

    def path_problem(self, waypoints: np.ndarray, carried: Carried | None = None, every: int = 1,
                     hand: bool = False) -> str | None:
        """The first problem along joint waypoints (every ``every``-th, and the last); None for none.

        Args:
            waypoints: (n, dof) joint positions.
            carried: what the hand holds along them, or None.
            every: how many waypoints apart the checks are.
            hand: whether the hand counts too (see `problem`).

        Returns:
            The reason, or None.
        """
        waypoints = np.atleast_2d(waypoints)
        if not waypoints.size:
            return None
        for k in np.unique(np.r_[np.arange(0, len(waypoints), every), len(waypoints) - 1]):
            problem = self.problem(waypoints[k], carried, hand)
            if problem is not None:
                return problem
        return None
