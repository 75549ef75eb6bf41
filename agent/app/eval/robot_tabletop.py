"""One tabletop variant explored by the robot in PyBullet, scored against the scene's ground truth.

The robot (`skills.robot.Robot`) knows the scene only through the bus: head and wrist frames,
the arm's state, the robot's description. The world runs in a thread of this process
(`local_world`), so that once the exploration is over the evaluation can read where every object
and part really ended up, which the agent never could.

To compare graphs, the explored graph's ids (the robot's memory ids) are put in the ground truth's
terms by the segmentation id each remembered instance was last seen with (`Instance.hint`). That id
is used here, for scoring only; the explorer and its skills never see it.
"""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from agent.acsg.decision import RuleDecisionModule
from agent.acsg.interactive_exploration import explore
from agent.acsg.graph import ACSG
from agent.acsg.json_format import acsg_from_dict, acsg_to_dict, from_ground_truth
from agent.acsg.metrics import episode_metrics
from skills.robot import Robot
from agent.perception.memory import InstanceMemory
from agent.app.runtime.local_world import local_world
from agent.app.eval.tabletop_recording import record_graph
from skills.skill_runs import SkillRuns
from worlds.bus.link import WorldLink
from worlds.facts import CLOSED_SHARE
from worlds.sim import World
from worlds.tabletop import tabletop_variant
from worlds.tabletop_scene import TabletopScene

#: An object back within this distance of where it stood counts as put back (the skills' own
#: acceptance: "put back within 2 cm").
PUT_BACK_M = 0.02


def run_robot(task: str, seed: int, recording: Path | None = None) -> dict[str, Any]:
    """Explore one tabletop variant with the robot; its Table I metrics and the skills' figures.

    Args:
        task: the tabletop task.
        seed: the variant's seed.
        recording: a folder to write the Rerun recording into (the explored graph, the arm's joints
            after each skill run), or None.

    Returns:
        The metrics and figures.
    """
    scene = tabletop_variant(task, seed)
    started = time.monotonic()
    with local_world() as served:
        link = WorldLink(served.session, served.keys, timeout_s=60.0)
        try:
            link.call("reset", {"seed": seed, "tabletop": task})
            start_positions, start_states = object_positions(served.world, scene), part_states(served.world, scene)
            robot = Robot(link)
            skill_runs = SkillRuns()
            if recording is not None:
                robot.body.skill_listeners.append(skill_runs)
            result = explore(robot, RuleDecisionModule(), robot)
            final_positions, final_states = object_positions(served.world, scene), part_states(served.world, scene)
        finally:
            link.close()
    explored = in_world_ids(result.graph, robot.memory)
    if recording is not None:
        planner = robot.body.context.planner
        skill_runs.joint_names = tuple(planner.joint_names) if planner is not None else ()
        record_graph(recording, f"{task}-{seed}-robot", explored, skill_runs)
    metrics = episode_metrics(explored, from_ground_truth(scene.ground_truth_acsg()), start_positions,
                              final_positions, start_states, final_states, tolerance_m=PUT_BACK_M)
    skills = robot.skill_times
    return {
        **asdict(metrics), "actions": len(result.steps()), "returned_to_start": result.returned_to_start,
        "failed_actions": [e.describe() for e in result.log if not e.ok],
        "skills": len(skills), "skills_ok": sum(r["ok"] for r in skills),
        "skill_seconds": round(sum(r["execution_s"] for r in skills), 2),
        "planning_ms": round(sum(r["planning_ms"] for r in skills), 1), "skill_times": skills,
        "seconds": round(time.monotonic() - started, 3),
    }


def object_positions(world: World, scene: TabletopScene) -> dict[str, np.ndarray]:
    """Instance id -> the object's centre now, for every small object of the scene.

    Args:
        world: the simulated world.
        scene: the tabletop scene.

    Returns:
        The positions.
    """
    return {str(obj.instance_id): np.asarray(world.object_position(obj.instance_id)) for obj in scene.objects}


def part_states(world: World, scene: TabletopScene) -> dict[str, float]:
    """Part instance id -> 1.0 open, 0.0 closed (within `CLOSED_SHARE` of its range from closed),
    -1.0 pushed in past its closed end by more than that share: not as it was, though not open.

    Args:
        world: the simulated world.
        scene: the tabletop scene.

    Returns:
        The states.
    """
    joints = world.part_states()
    states = {}
    for _, placement in scene.storage:
        ids = placement.part_ids()
        for part in placement.model.parts:
            value = joints[placement.furniture_id][part.name]
            share = CLOSED_SHARE * (part.upper - part.lower)
            states[str(ids[part.name])] = 1.0 if value > part.lower + share else -1.0 if value < part.lower - share else 0.0
    return states


def in_world_ids(graph: ACSG, memory: InstanceMemory) -> ACSG:
    """``graph`` with its memory ids replaced by the segmentation ids they were last seen with.

    Ids whose segmentation id is unknown, or already taken by another instance (the memory split
    one thing in two), keep their memory id prefixed with ``m``: they cannot match the ground
    truth and count against the exploration, as they should.

    Args:
        graph: the explored graph, in memory ids.
        memory: the robot's instance memory.

    Returns:
        The renamed graph.
    """
    taken: set[str] = set()
    names: dict[str, str] = {}  # old node id -> new, objects first (actions are named after them)
    for node in graph.objects():
        try:
            hint = memory.get(int(node.instance)).hint if node.instance is not None else None
        except (KeyError, ValueError):
            hint = None
        world_id = f"m{node.instance}" if hint is None or str(hint) in taken else str(hint)
        taken.add(world_id)
        names[node.id] = f"o{world_id}"
    data = acsg_to_dict(graph)
    for node in data["nodes"]:
        old = node["id"]
        if node["kind"] == "object":
            node["id"] = names[old]
            node["instance"] = node["id"][1:]
        else:
            node["target"] = names[node["target"]]
            node["id"] = names[old] = f"{old.partition(':')[0]}:{node['target'][1:]}"
            handle = node.get("params", {}).get("handle")
            if handle in names:
                node["params"]["handle"] = names[handle]
    for edge in data["edges"]:
        edge["source"], edge["target"] = names[edge["source"]], names[edge["target"]]
    return acsg_from_dict(data)
