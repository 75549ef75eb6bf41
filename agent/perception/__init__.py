"""Perception for interactive exploration (RoboEXP): instance memory over views, and part geometry.

Pure numpy/scipy, no simulator and no bus: frames in, instances and TCP poses out, all in the
world frame. `memory` fuses segmented RGB-D frames into the voxel `instances`, merging by label
and `overlap`, forgetting by the depth test of `staleness`, attaching parts to their
`part_parents`. `part_geometry` reads a handle and its front into a door or drawer (with
`directions` measuring axes and normals), `part_motion` says how opening moves it, `grasp_poses`
where the TCP goes to open or close it, and `opening` how far a view shows it open. `sightings`
keeps where pieces of one kind of storage were seen, from farther than the memory looks; `rooms`
reads which room each part of a frame shows off the furniture standing there.
"""

from agent.perception.directions import GeometryError, front_normal, principal_axis
from agent.perception.grasp_poses import (
    closing_waypoints,
    grasp_pose,
    grasp_rotation,
    opening_waypoints,
    pregrasp_pose,
    top_grasp_point,
)
from agent.perception.instances import FrameUpdate, Instance, MemoryConfig
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import PartGeometry, classify_part, handle_geometry, part_geometry
from agent.perception.part_motion import moved_geometry

__all__ = [
    "FrameUpdate",
    "GeometryError",
    "Instance",
    "InstanceMemory",
    "MemoryConfig",
    "PartGeometry",
    "classify_part",
    "closing_waypoints",
    "front_normal",
    "grasp_pose",
    "grasp_rotation",
    "handle_geometry",
    "moved_geometry",
    "opening_waypoints",
    "part_geometry",
    "pregrasp_pose",
    "principal_axis",
    "top_grasp_point",
]
