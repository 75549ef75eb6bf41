"""The arm's links as spheres: along their skeleton, and where they bulge out of the tube round it.

`skills.arm.clearance` strings spheres of `LINK_RADIUS_M` along the skeleton, the lines between
the joints' origins (`link_spheres`, fixed to each link once: `link_tubes`). Most of a link lies within that tube, but not all: the Panda's wrist housing
(link 5) hangs 10 cm below the forearm's axis, where it caught a box's corner that the tube kept
clear of. Here each link's collision mesh, read from the URDF, is checked against its own stretch
of the skeleton, and the vertices outside the tube get spheres of their own, fixed to the link.

Pure: URDF text and mesh files in, points in each link's frame out.
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from skills.arm.kinematics import ArmKinematics
from skills.arm.segments import nearest_on_segments

log = logging.getLogger(__name__)

#: The links' radius around their skeleton (m).
LINK_RADIUS_M = 0.065
#: The spacing of the spheres along each segment of the skeleton (m).
SPHERE_STEP_M = 0.04
#: A vertex within this of the tube or of a bulge's sphere counts as covered (m): the mesh is a
#: link's outline, not a thing to follow to the millimetre.
SLACK_M = 0.01


def link_spheres(skeleton: np.ndarray, step_m: float = SPHERE_STEP_M) -> np.ndarray:
    """Sphere centres along the segments between successive points of the arm's skeleton.

    Args:
        skeleton: (k, 3) points along the chain, shoulder first.
        step_m: the most the centres lie apart along a segment.

    Returns:
        (M, 3) centres: each point, and points between successive ones.
    """
    skeleton = np.asarray(skeleton, dtype=float)
    centres = [skeleton[:1]]
    for start, end in zip(skeleton[:-1], skeleton[1:]):
        count = max(1, math.ceil(float(np.linalg.norm(end - start)) / step_m))
        centres.append(start + np.outer(np.arange(1, count + 1) / count, end - start))
    return np.vstack(centres)


def _rotation_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """The URDF's fixed-axis roll, pitch, yaw as a 3×3 rotation."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _obj_vertices(path: Path) -> np.ndarray:
    """The ``v`` lines of a Wavefront OBJ file."""
    rows = [line.split()[1:4] for line in path.read_text(errors="replace").splitlines() if line.startswith("v ")]
    return np.array(rows, dtype=float).reshape(-1, 3)


def collision_vertices(urdf_xml: str, joint: str) -> np.ndarray | None:
    """The collision mesh vertices of the link ``joint`` moves, in that link's frame.

    Args:
        urdf_xml: the robot's URDF text.
        joint: a joint of it.

    Returns:
        (N, 3) vertices; None when the link has no OBJ collision mesh that can be read here (a
        robot described from another machine names files of that machine).
    """
    root = ET.fromstring(urdf_xml)
    child = next((j.find("child") for j in root.iter("joint") if j.get("name") == joint), None)
    link = next((k for k in root.iter("link") if child is not None and k.get("name") == child.get("link")), None)
    meshes = [] if link is None else [c for c in link.iter("collision") if c.find("geometry/mesh") is not None]
    vertices = []
    for collision in meshes:
        mesh = collision.find("geometry/mesh")
        path = Path(mesh.get("filename", "").removeprefix("file://"))
        if path.suffix.lower() != ".obj" or not path.is_file():
            log.warning("link shells: %s's collision mesh %s cannot be read here; its link is kept to the "
                        "tube round the skeleton", joint, path)
            return None
        scale = np.array((mesh.get("scale") or "1 1 1").split(), dtype=float)
        origin = collision.find("origin")
        xyz = np.array(((origin.get("xyz") if origin is not None else None) or "0 0 0").split(), dtype=float)
        rpy = np.array(((origin.get("rpy") if origin is not None else None) or "0 0 0").split(), dtype=float)
        vertices.append((_obj_vertices(path) * scale) @ _rotation_rpy(*rpy).T + xyz)
    return np.vstack(vertices) if vertices else None


def bulge_centres(vertices: np.ndarray, segments: np.ndarray, radius: float = LINK_RADIUS_M,
                  slack: float = SLACK_M) -> np.ndarray:
    """Sphere centres that, with the tube of ``radius`` round ``segments``, cover a link's vertices.

    Greedy: the vertex farthest out of what is covered gets a sphere whose surface reaches it, its
    centre on the way from the line to it; the vertices that sphere covers are done, and so on.

    Args:
        vertices: (N, 3) the link's vertices, in its frame.
        segments: (m ≥ 1, 2, 3) the skeleton's segments that move with the link, in its frame.
        radius: the tube's and the spheres' radius (m).
        slack: how far out of them a vertex may still count as covered (m).

    Returns:
        (M, 3) centres, in the link's frame; none for a link within its tube.
    """
    feet = nearest_on_segments(vertices, segments)
    out = np.linalg.norm(vertices - feet, axis=1) > radius + slack
    left, feet = vertices[out], feet[out]
    centres = []
    while len(left):
        gaps = np.linalg.norm(left - feet, axis=1)
        far = int(np.argmax(gaps))
        centre = feet[far] + (left[far] - feet[far]) * (gaps[far] - radius) / gaps[far]
        centres.append(centre)
        keep = np.linalg.norm(left - centre, axis=1) > radius + slack
        left, feet = left[keep], feet[keep]
    return np.array(centres).reshape(-1, 3)


def rigid_segments(kin: ArmKinematics, first: int, postures: np.ndarray) -> list[np.ndarray]:
    """For each link of the skeleton, the skeleton's segments that keep still in its frame: its own
    stretch, and a neighbour's where that runs along the joint between them (the Panda's forearm,
    drawn from the elbow, runs along the wrist's first axis, down the middle of link 5's mesh).

    Args:
        kin: the arm's kinematics.
        first: the first joint of the skeleton.
        postures: (p ≥ 2, dof) joint positions to compare the segments at.

    Returns:
        (m, 2, 3) segments in each link's frame, in the order of ``kin.link_lines(first)``.
    """
    seen = []
    for q in postures:
        frames = kin.link_frames(q, first)
        world = [line @ frame[:3, :3].T + frame[:3, 3] for frame, (_, line) in zip(frames, kin.link_lines(first))]
        ends = np.array([(a, b) for line in world for a, b in zip(line[:-1], line[1:])])
        seen.append([(ends - frame[:3, 3]) @ frame[:3, :3] for frame in frames[:len(world)]])
    rigid = []
    for k in range(len(seen[0])):
        local = np.array([posture[k] for posture in seen])  # (p, m, 2, 3)
        still = np.abs(local - local[0]).max(axis=(0, 2, 3)) < 1e-6
        rigid.append(local[0][still])
    return rigid


def link_tubes(kin: ArmKinematics, first: int) -> list[np.ndarray]:
    """Each link's `link_spheres` along its stretch of `ArmKinematics.link_lines` from ``first``, in
    its own frame: worked out once, moved with the link at each posture.

    Args:
        kin: the arm's kinematics.
        first: the first joint of the skeleton.

    Returns:
        (M, 3) centres in each link's frame, its joint's origin left out (the link before ends
        there; the first joint's origin is the caller's).
    """
    return [link_spheres(line)[1:] for _, line in kin.link_lines(first)]


def link_bulges(urdf_xml: str, kin: ArmKinematics, first: int, seed: int = 0) -> list[np.ndarray]:
    """Each link's bulge spheres (`bulge_centres`) along `ArmKinematics.link_lines` from ``first``.

    Args:
        urdf_xml: the robot's URDF text.
        kin: the arm's kinematics, of that URDF.
        first: the first joint of the skeleton.
        seed: seeds the postures `rigid_segments` compares.

    Returns:
        (M, 3) centres in each link's frame, in the order of ``kin.link_lines(first)``; none for a
        link whose mesh cannot be read.
    """
    postures = np.random.default_rng(seed).uniform(kin.lower, kin.upper, size=(3, kin.dof))
    bulges = []
    for (joint, _), segments in zip(kin.link_lines(first), rigid_segments(kin, first, postures)):
        vertices = collision_vertices(urdf_xml, joint)
        bulges.append(np.zeros((0, 3)) if vertices is None else bulge_centres(vertices, segments))
    return bulges
