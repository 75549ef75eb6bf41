"""Geometry of doors and drawers from their points, and the TCP paths that open and close them.

RoboEXP's action module (App. D) reads everything it needs from perception, not from a model of
the furniture:

- the handle's direction is the first principal axis of its points; the paper snaps it to vertical
  when |axis·z| > 0.7 and flattens it to horizontal otherwise;
- the default rule tells the joint from the handle: a **horizontal handle means a drawer**
  (prismatic: pulled straight out), a **vertical handle means a door** (revolute about a vertical
  hinge). It is a convention of furniture makers, not physics: a caller that knows better (a
  detector that says "door" for a bottom-hinged flap with a horizontal handle) passes ``kind``;
  a door with a horizontal handle then turns about a horizontal hinge at the edge farthest from it;
- the opening direction is the most common surface normal of the front near the handle, turned
  towards the robot (the camera): the front faces whoever can see it;
- a door's hinge is on the side of its front farther from the handle (a handle sits near the
  free edge, where it gives the most leverage), along the front's outer face, parallel to the
  handle. Its axis is signed so that opening is a positive rotation about it (right-hand rule)
  that swings the handle outwards, along the normal.

Frames: every point, direction and pose is in the world frame (z up), metres and radians.

TCP convention (what the kinematics takes as targets). A TCP pose is a 4x4 world transform whose
rotation columns are the gripper's axes:

- z (approach) = -normal: the gripper comes at the front from outside, pointing into it;
- x = the handle's axis: the bar lies along x, between the fingers;
- y = z × x: the fingers close along y, across the bar;
- the origin is the grasp point: the centre of the handle's points.

The grasp is symmetric under a half turn about z (x, y -> -x, -y); an arm may take whichever of
the two suits its joint limits. Along an opening, the TCP rides with the part: a drawer's TCP keeps
its orientation and moves along the normal; a door's TCP turns with the door about the hinge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

if TYPE_CHECKING:
    from agent.perception.memory import InstanceMemory

UP = np.array([0.0, 0.0, 1.0])
#: |axis·z| above this is a vertical handle (the paper's threshold).
VERTICAL_COS = 0.7
#: The paper's revolute step, and ours for drawers (2 cm), when no step count is given.
DOOR_STEP_RAD = math.radians(5.0)
DRAWER_STEP_M = 0.02
#: Pre-grasp stand-off along the normal (the paper's 3 cm).
PREGRASP_M = 0.03
KINDS = ("door", "drawer")


class GeometryError(ValueError):
    """Points that do not determine the geometry asked for; the text names the input."""


@dataclass(frozen=True, eq=False)  # arrays inside: compare fields with numpy, not ==
class PartGeometry:
    """A door or drawer as perception sees it (world frame; unit vectors).

    ``handle_point``: centre of the handle's points (the grasp point). ``handle_axis``: the bar's
    direction, snapped vertical (+z) or horizontal. ``normal``: outward front normal, towards the
    robot: the direction a drawer slides out and a door's free edge first moves. For doors,
    ``hinge_point`` is the point of the hinge line level with the handle, on the front's outer
    face, and ``hinge_axis`` the line's direction, signed so that opening is a positive rotation
    about it; both are None for drawers. ``width``: for doors, how far the front reaches from the
    hinge line (to its free edge, a little beyond the handle): the radius of what the door sweeps
    as it swings, which whoever opens it must stand clear of; None when unknown. ``front_depth``:
    how far the front's outer face lies behind the handle point (along -``normal``): the room
    between bar and front that a hand coming down on the bar from above must keep out of; None
    when unknown.
    """

    kind: str
    handle_point: np.ndarray
    handle_axis: np.ndarray
    normal: np.ndarray
    hinge_point: np.ndarray | None = None
    hinge_axis: np.ndarray | None = None
    width: float | None = None
    front_depth: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise GeometryError(f"kind: {self.kind!r} is not one of {KINDS}")
        if self.kind == "door" and (self.hinge_point is None or self.hinge_axis is None):
            raise GeometryError("hinge_point, hinge_axis: a door needs both")

    @property
    def joint(self) -> str:
        """'revolute' for doors, 'prismatic' for drawers."""
        return "revolute" if self.kind == "door" else "prismatic"

    @property
    def radius(self) -> float:
        """Distance from the handle to the hinge line (0 for drawers)."""
        if self.hinge_point is None or self.hinge_axis is None:
            return 0.0
        return _distance_to_line(self.handle_point, self.hinge_point, self.hinge_axis)

    @property
    def swing_radius(self) -> float:
        """How far from the hinge line the door's front reaches as it swings: its `width` when seen,
        else the handle's radius (0 for drawers)."""
        return max(self.radius, self.width or 0.0)


# --- directions --------------------------------------------------------------------------------


def principal_axis(points: np.ndarray) -> np.ndarray:
    """First PCA axis of (N, 3) points, unit, signed so its largest component is positive."""
    pts = _points(points, "points", minimum=2)
    _, _, vt = np.linalg.svd(pts - pts.mean(axis=0), full_matrices=False)
    return _signed(vt[0])


def snap_handle_axis(axis: np.ndarray, vertical_cos: float = VERTICAL_COS) -> np.ndarray:
    """The paper's snap: +z when |axis·z| > ``vertical_cos``, else the axis flattened to horizontal."""
    axis = _unit(axis, "axis")
    if abs(axis[2]) > vertical_cos:
        return UP.copy()
    return _signed(_unit(np.array([axis[0], axis[1], 0.0]), "axis (flattened)"))


def classify_part(handle_axis: np.ndarray, vertical_cos: float = VERTICAL_COS) -> str:
    """'door' for a vertical handle, 'drawer' for a horizontal one (the default rule, see module doc)."""
    return "door" if abs(_unit(handle_axis, "handle_axis")[2]) > vertical_cos else "drawer"


def plane_normal(points: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """Smallest PCA axis of (N, 3) points, turned to face the point ``toward`` (e.g. the camera)."""
    pts = _points(points, "points", minimum=3)
    centre = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - centre, full_matrices=False)
    normal = vt[2]
    return normal if normal @ (np.asarray(toward, float) - centre) >= 0 else -normal


def surface_normals(points: np.ndarray, toward: np.ndarray, k: int = 16) -> np.ndarray:
    """Per-point normals (N, 3): smallest PCA axis of each point's ``k`` nearest, facing ``toward``."""
    pts = _points(points, "points", minimum=3)
    k = min(k, len(pts))
    _, neighbours = cKDTree(pts).query(pts, k=k)
    local = pts[neighbours] - pts[neighbours].mean(axis=1, keepdims=True)
    _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))
    normals = vectors[:, :, 0]  # eigh sorts eigenvalues ascending
    flip = np.einsum("ni,ni->n", normals, np.asarray(toward, float) - pts) < 0
    normals[flip] *= -1
    return normals


def front_normal(points: np.ndarray, toward: np.ndarray, level: bool = True,
                 tolerance_deg: float = 15.0, k: int = 16) -> np.ndarray:
    """The most common surface normal of ``points``, facing ``toward`` (the paper's opening direction).

    The mode, not the mean, because the points of a front near a handle include its edges and the
    carcass beside it, whose normals point sideways. ``level`` drops the vertical component:
    storage stands upright, so a front's normal is horizontal and any tilt is noise.
    """
    pts = _points(points, "points", minimum=3)
    normals = surface_normals(pts, toward, k) if len(pts) > k else plane_normal(pts, toward)[None, :]
    cos = math.cos(math.radians(tolerance_deg))
    candidates = normals[np.linspace(0, len(normals) - 1, min(len(normals), 400)).astype(int)]
    support = (candidates @ normals.T > cos).sum(axis=1)
    best = candidates[int(np.argmax(support))]
    normal = _unit(normals[normals @ best > cos].mean(axis=0), "normals")
    if level:
        normal = _unit(np.array([normal[0], normal[1], 0.0]), "normal (levelled): the front is horizontal")
    return normal


# --- parts -------------------------------------------------------------------------------------


def part_geometry(
    handle_points: np.ndarray,
    front_points: np.ndarray,
    toward: np.ndarray,
    kind: str | None = None,
    vertical_cos: float = VERTICAL_COS,
    level: bool = True,
    near_m: float = 0.15,
) -> PartGeometry:
    """The geometry of the door or drawer whose handle and front are given (world frame).

    ``front_points``: the moving part's front (its own instance; the parent's points near the
    handle do for the normal, but a door's hinge needs the door's own extent). ``toward``: where
    the robot sees from (the camera position), to orient the normal. ``kind`` overrides the
    handle rule. The normal is taken from the front points within ``near_m`` of the handle (all of
    them if fewer than 10 lie that close).
    """
    handle = _points(handle_points, "handle_points", minimum=2)
    front = _points(front_points, "front_points", minimum=3)
    if kind is not None and kind not in KINDS:
        raise GeometryError(f"kind: {kind!r} is not one of {KINDS}")
    handle_point = handle.mean(axis=0)
    axis = snap_handle_axis(principal_axis(handle), vertical_cos)
    kind = kind or classify_part(axis, vertical_cos)
    near = front[np.linalg.norm(front - handle_point, axis=1) <= near_m]
    around = near if len(near) >= 10 else front
    normal = front_normal(around, toward, level)
    axis = _unit(axis - (axis @ normal) * normal, "handle_axis: parallel to the front normal")
    depth = -float(np.median((around - handle_point) @ normal))
    if kind == "drawer":
        return PartGeometry("drawer", handle_point, axis, normal, front_depth=depth)
    hinge_point = hinge_line_point(front, handle_point, axis, normal)
    return PartGeometry("door", handle_point, axis, normal, hinge_point, hinge_axis(handle_point, hinge_point, normal),
                        door_width(front, handle_point, hinge_point, axis, normal), depth)


def hinge_line_point(front_points: np.ndarray, handle_point: np.ndarray, handle_axis: np.ndarray,
                     normal: np.ndarray) -> np.ndarray:
    """Where the hinge line passes level with the handle: the front's edge farther from the handle.

    The front's points are measured across the handle (in the front's plane, perpendicular to the
    bar); the edge is the 1st or 99th percentile, whichever lies farther from the handle, so a few
    stray points do not move it. The point lies on the front's outer face (median depth along the
    normal), where the hinges of a storage door sit.
    """
    front = _points(front_points, "front_points", minimum=3)
    across = _unit(np.cross(normal, handle_axis), "handle_axis x normal")
    offsets = (front - handle_point) @ across
    lo, hi = np.percentile(offsets, [1.0, 99.0])
    edge = lo if -lo > hi else hi
    face = float(np.median((front - handle_point) @ normal))
    return handle_point + edge * across + face * normal


def door_width(front_points: np.ndarray, handle_point: np.ndarray, hinge_point: np.ndarray,
               handle_axis: np.ndarray, normal: np.ndarray) -> float:
    """How far a door's front reaches from its hinge line, across the handle: the 99th percentile of
    its points' offsets that way (stray points aside), never less than the handle's own offset."""
    front = _points(front_points, "front_points", minimum=3)
    across = _unit(np.cross(normal, handle_axis), "handle_axis x normal")
    toward_handle = 1.0 if (np.asarray(handle_point, float) - hinge_point) @ across >= 0 else -1.0
    offsets = toward_handle * ((front - hinge_point) @ across)
    return float(max(np.percentile(offsets, 99.0), toward_handle * (handle_point - hinge_point) @ across))


def hinge_axis(handle_point: np.ndarray, hinge_point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The hinge direction about which a positive rotation swings the handle out along ``normal``.

    With r the in-plane direction from the hinge to the handle, (r, normal, axis) is right-handed:
    axis = r × normal, so axis × r = normal is the handle's initial velocity.
    """
    r = np.asarray(handle_point, float) - np.asarray(hinge_point, float)
    r = r - (r @ normal) * normal
    return _unit(np.cross(_unit(r, "handle_point - hinge_point"), normal), "hinge axis")


def top_grasp_point(points: np.ndarray, band_m: float = 0.01) -> np.ndarray:
    """The paper's top-down pick point: the mean of the points within ``band_m`` of the highest."""
    pts = _points(points, "points", minimum=1)
    return pts[pts[:, 2] >= pts[:, 2].max() - band_m].mean(axis=0)


def handle_geometry(memory: InstanceMemory, handle_id: int, toward: np.ndarray, kind: str | None = None,
                    **options: float | bool) -> PartGeometry:
    """`part_geometry` of a remembered handle and the part it is attached to (its parent)."""
    handle = memory.get(handle_id)
    if handle.parent is None:
        raise GeometryError(f"handle_id: instance {handle.id} ({handle.label}) has no parent part")
    part = memory.get(handle.parent)
    return part_geometry(handle.points(), part.points(), toward, kind, **options)  # type: ignore[arg-type]


# --- TCP poses ---------------------------------------------------------------------------------


def grasp_rotation(geometry: PartGeometry) -> np.ndarray:
    """3x3 TCP orientation at the handle: columns x = handle axis, y = z × x, z = -normal."""
    z = -geometry.normal
    x = _unit(geometry.handle_axis - (geometry.handle_axis @ z) * z, "handle_axis")
    return np.column_stack([x, np.cross(z, x), z])


def grasp_pose(geometry: PartGeometry) -> np.ndarray:
    """4x4 TCP pose closing on the handle (see the module doc for the axes)."""
    return _pose(grasp_rotation(geometry), geometry.handle_point)


def pregrasp_pose(geometry: PartGeometry, standoff_m: float = PREGRASP_M) -> np.ndarray:
    """The grasp pose backed off ``standoff_m`` along the normal: where the approach starts."""
    return _pose(grasp_rotation(geometry), geometry.handle_point + standoff_m * geometry.normal)


def opening_waypoints(geometry: PartGeometry, amount: float, n: int | None = None) -> list[np.ndarray]:
    """TCP poses (n + 1 of them, 4x4) from the grasp to the part opened by ``amount``.

    ``amount`` is radians for a door (about ``hinge_axis``), metres for a drawer (along
    ``normal``); a negative amount moves the other way (closing a part whose geometry was taken
    while it stood open). ``n`` steps of equal size; by default 5° or 2 cm per step. The first pose
    is `grasp_pose`; a door's TCP turns with the door, so the fingers stay across the bar.
    """
    steps = _steps(geometry, amount, n)
    start = grasp_pose(geometry)
    poses = []
    for value in np.linspace(0.0, amount, steps + 1):
        poses.append(part_motion(geometry, float(value)) @ start)
    return poses


def closing_waypoints(geometry: PartGeometry, amount: float, n: int | None = None) -> list[np.ndarray]:
    """TCP poses from the part opened by ``amount`` back to closed: `opening_waypoints` reversed.

    ``geometry`` is the part as seen closed (what `part_geometry` measured before opening it).
    """
    return opening_waypoints(geometry, amount, n)[::-1]


def moved_geometry(geometry: PartGeometry, amount: float) -> PartGeometry:
    """The geometry of the part after opening it by ``amount``: handle and normal carried along."""
    move = part_motion(geometry, amount)
    rotation = move[:3, :3]
    return PartGeometry(geometry.kind, move[:3, :3] @ geometry.handle_point + move[:3, 3],
                        rotation @ geometry.handle_axis, rotation @ geometry.normal,
                        geometry.hinge_point, geometry.hinge_axis, geometry.width, geometry.front_depth)


#: How far a part is opened when the target does not say: RoboEXP pulls drawers 0.2-0.4 m and
#: swings doors in 5° steps; 75° lets the wrist camera see past the door into the shelves. Here, not
#: with the skills, so that what an opening sweeps is planned (`agent.acsg.keep_clear`) without them.
DEFAULT_AMOUNT = {"drawer": 0.2, "door": math.radians(75.0)}


def fit_opening(geometry: PartGeometry, closed_points: np.ndarray, seen_points: np.ndarray, most: float,
                steps: int = 80) -> tuple[float, float]:
    """How far the part stands open, from a view of it: the opening in [0, ``most``] that carries the
    part's points as seen closed (``closed_points``) best onto the points seen now (``seen_points``,
    often only part of it), scored by the median distance from each seen point to the carried
    ones. Returns (opening, that median distance in m).

    What a skill's own account of the motion cannot tell: a part held back (by the end of its
    travel, by the robot's own body in a door's swing) stops there while the hand pulls on.
    """
    from scipy.spatial import cKDTree

    closed = _points(closed_points, "closed_points", 3)
    seen = _points(seen_points, "seen_points", 3)
    best = (0.0, math.inf)
    for amount in np.linspace(0.0, float(most), steps + 1):
        motion = part_motion(geometry, float(amount))
        distance, _ = cKDTree(closed @ motion[:3, :3].T + motion[:3, 3]).query(seen)
        score = float(np.median(distance))
        if score < best[1]:
            best = (float(amount), score)
    return best


def opening_seen(geometry: PartGeometry, closed_points: np.ndarray, views: Sequence[np.ndarray], reported: float,
                 near_m: float, fit_m: float) -> float | None:
    """How far the part stands open by the view of it among ``views`` (point sets of the part's kind
    seen now): those whose centre lies within ``near_m`` of where ``reported`` would carry the part,
    nearest first, and the first that `fit_opening` (up to a quarter beyond ``reported``) carries
    its points onto within ``fit_m`` (median). None when no view is of this part: with the part's own
    view hidden (behind the arm, say), the nearest may be its neighbour's, a drawer's height away,
    which no opening fits."""
    closed = _points(closed_points, "closed_points", 3)
    motion = part_motion(geometry, reported)
    expected = motion[:3, :3] @ closed.mean(axis=0) + motion[:3, 3]
    near = sorted((float(np.linalg.norm(points.mean(axis=0) - expected)), k) for k, points in enumerate(views)
                  if len(points) >= 3)
    for distance, k in near:
        if distance > near_m:
            break
        amount, misfit = fit_opening(geometry, closed, views[k], 1.25 * reported)
        if misfit <= fit_m:
            return amount
    return None


def part_motion(geometry: PartGeometry, amount: float) -> np.ndarray:
    """4x4 rigid motion of the part opened by ``amount`` (world frame, applied on the left): what
    carries the closed part's points, handle and anything fixed to it to where they are now."""
    move = np.eye(4)
    if geometry.kind == "drawer":
        move[:3, 3] = amount * geometry.normal
        return move
    assert geometry.hinge_point is not None and geometry.hinge_axis is not None
    rotation = rotation_about(geometry.hinge_axis, amount)
    move[:3, :3] = rotation
    move[:3, 3] = geometry.hinge_point - rotation @ geometry.hinge_point
    return move


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` radians about the unit ``axis`` (Rodrigues)."""
    k = _unit(axis, "axis")
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def _steps(geometry: PartGeometry, amount: float, n: int | None) -> int:
    if n is not None:
        if int(n) != n or n < 1:
            raise GeometryError(f"n: {n!r} must be a positive number of steps")
        return int(n)
    step = DOOR_STEP_RAD if geometry.kind == "door" else DRAWER_STEP_M
    return max(1, math.ceil(abs(amount) / step - 1e-9))


def _pose(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, position
    return pose


def _distance_to_line(point: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    d = np.asarray(point, float) - np.asarray(origin, float)
    return float(np.linalg.norm(d - (d @ direction) * direction))


def _points(points: np.ndarray, name: str, minimum: int) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise GeometryError(f"{name}: shape {pts.shape}, expected (N, 3)")
    if len(pts) < minimum:
        raise GeometryError(f"{name}: {len(pts)} points, need at least {minimum}")
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{name}: not all finite")
    return pts


def _unit(vector: np.ndarray, name: str) -> np.ndarray:
    v = np.asarray(vector, dtype=float)
    norm = float(np.linalg.norm(v))
    if not norm > 1e-9:
        raise GeometryError(f"{name}: zero-length direction")
    return v / norm


def _signed(vector: np.ndarray) -> np.ndarray:
    """The direction with its largest-magnitude component positive: one sign for a sign-free axis."""
    return vector if vector[int(np.argmax(np.abs(vector)))] >= 0 else -vector
