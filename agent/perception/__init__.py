"""Perception for interactive exploration (RoboEXP): instance memory over views, and part geometry.

Pure numpy/scipy, no simulator and no bus: frames in, instances and TCP poses out, all in the
world frame. `memory` fuses segmented RGB-D frames into voxel instances (merge by label and
overlap, forget by depth test, attach parts to their parents); `geometry` reads a handle and its
front into a door or drawer and the TCP waypoints that open or close it; `sightings` keeps where
pieces of one kind of storage were seen, from farther than the memory looks; `rooms` reads which
room each part of a frame shows off the furniture standing there.
"""

from agent.perception.geometry import (
    GeometryError,
    PartGeometry,
    classify_part,
    closing_waypoints,
    front_normal,
    grasp_pose,
    grasp_rotation,
    handle_geometry,
    moved_geometry,
    opening_waypoints,
    part_geometry,
    pregrasp_pose,
    principal_axis,
    top_grasp_point,
)
from agent.perception.memory import FrameUpdate, Instance, InstanceMemory, MemoryConfig

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
