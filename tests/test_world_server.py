"""The world server over real Zenoh on loopback, with a real PyBullet world behind it."""

from __future__ import annotations

import math
import os
import signal
import struct
import subprocess
import sys
import threading
import uuid
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
import zenoh

from worlds.bus.codec import decode
from worlds.bus.keys import Keys
from worlds.bus.liveness import LivenessWatch
from worlds.bus.rpc import QueryFailed, call
from worlds.bus.session import free_tcp_endpoint, open_session
from worlds.freespace import clearance
from worlds.home import generate_home
from worlds.robot import ROBOT_RADIUS, CameraConfig, camera_pose
from worlds.scenario import make_scenario
from worlds.server import WorldServer
from worlds.spec import dump_spec
from worlds.things import point_rect_distance

World = tuple[zenoh.Session, Keys]
SEED = 3


def _cmd(world: World, verb: str, meta: dict | None = None):
    session, keys = world
    return call(session, keys.world_cmd(verb), meta or {}, timeout_s=10.0)


def _back_project(depth: np.ndarray, camera: dict, pose: np.ndarray) -> np.ndarray:
    """World points (H, W, 3) of every pixel, through pixel centres (u = column + 0.5)."""
    rows, cols = np.indices(depth.shape)
    z = depth.astype(float)
    x = (cols + 0.5 - camera["cx"]) * z / camera["fx"]
    y = (rows + 0.5 - camera["cy"]) * z / camera["fy"]
    return (np.stack([x, y, z, np.ones_like(z)], axis=-1) @ pose.T)[..., :3]


def _box_distance(point: np.ndarray, center: tuple[float, ...], size: tuple[float, ...]) -> np.ndarray:
    half = np.array(size) / 2
    return np.linalg.norm(np.maximum(np.abs(point - np.array(center)) - half, 0.0), axis=-1)


def test_reset_replies_with_scenario_home_and_pose(world: World) -> None:
    reply = _cmd(world, "reset", {"seed": SEED})
    home = generate_home(SEED)
    scenario = make_scenario(home, SEED).to_dict()
    assert reply.meta["scenario"] == scenario
    assert {"question", "choices", "answer", "kind", "budget", "start_pose", "seed"} <= set(scenario)
    assert reply.meta["home"] == {
        "area_m2": home.area_m2,
        "bounds": list(home.bounds),
    }  # rooms are ground truth: only the episode report, which no behaviour reads, names them
    assert reply.meta["base_pose"] == pytest.approx(scenario["start_pose"])


def test_observe_frames_agree_with_the_camera_and_labels(world: World) -> None:
    _cmd(world, "reset", {"seed": SEED})
    first, frame = _cmd(world, "observe"), _cmd(world, "observe")
    assert (first.meta["observation"], frame.meta["observation"]) == (1, 2)
    camera = frame.meta["camera"]
    config = CameraConfig()
    assert camera == pytest.approx(config.to_dict())
    assert camera["fx"] == pytest.approx(camera["width"] / 2 / math.tan(math.radians(camera["hfov_deg"]) / 2))
    h, w = camera["height"], camera["width"]
    rgb, depth, seg = frame.arrays["rgb"], frame.arrays["depth"], frame.arrays["seg"]
    assert (rgb.shape, rgb.dtype) == ((h, w, 3), np.uint8)
    assert (depth.shape, depth.dtype) == ((h, w), np.float32)
    assert (seg.shape, seg.dtype) == ((h, w), np.int32)
    pose = np.array(frame.meta["camera_pose"])
    assert pose == pytest.approx(camera_pose(tuple(frame.meta["base_pose"]), config))
    present = set(np.unique(seg).tolist()) - {-1}
    assert {label["id"] for label in frame.meta["labels"]} == present
    truth = generate_home(SEED).labels()
    assert all(label == truth[label["id"]] for label in frame.meta["labels"])
    assert frame.meta["render_ms"] > 0
    assert ((depth > 0) | (seg == -1)).all() and (depth <= camera["far"]).all()


def test_depth_back_projects_onto_the_surfaces_seen(world: World) -> None:
    home = generate_home(SEED)
    reset = _cmd(world, "reset", {"seed": SEED})
    x, y, _ = reset.meta["base_pose"]
    rooms = {room.instance_id: room for room in home.rooms}
    walls = {wall.instance_id: wall for wall in home.walls}
    checked = {"floor": 0, "wall": 0}
    for yaw in (0.0, math.pi / 2, math.pi, -math.pi / 2):
        assert _cmd(world, "move_base", {"path": [[x, y]], "yaw": yaw}).meta["reached"]
        frame = _cmd(world, "observe")
        depth, seg = frame.arrays["depth"], frame.arrays["seg"]
        points = _back_project(depth, frame.meta["camera"], np.array(frame.meta["camera_pose"]))
        for instance, room in rooms.items():
            mask = (seg == instance) & (depth > 0)
            floor = points[mask]
            assert np.abs(floor[:, 2]).max(initial=0.0) < 0.02
            assert all(point_rect_distance(px, py, room.rect) < 0.02 for px, py, _ in floor[::50])
            checked["floor"] += int(mask.sum())
        for instance, wall in walls.items():
            mask = (seg == instance) & (depth > 0)
            assert _box_distance(points[mask], wall.center, wall.size).max(initial=0.0) < 0.02
            checked["wall"] += int(mask.sum())
    assert checked["floor"] > 1000 and checked["wall"] > 1000, checked


def test_move_base_reaches_free_targets_and_stops_at_walls(world: World) -> None:
    home = generate_home(SEED)
    x, y, _ = _cmd(world, "reset", {"seed": SEED}).meta["base_pose"]
    heading = _clear_heading(home, x, y)
    ahead = [x + 0.3 * math.cos(heading), y + 0.3 * math.sin(heading)]
    moved = _cmd(world, "move_base", {"path": [ahead], "yaw": 1.0}).meta
    assert moved["reached"] and moved["contact"] is None
    assert moved["base_pose"] == pytest.approx([*ahead, 1.0])
    assert moved["travelled_m"] == pytest.approx(0.3)

    far = [ahead[0] + 30 * math.cos(heading), ahead[1] + 30 * math.sin(heading)]
    bumped = _cmd(world, "move_base", {"path": [far]}).meta
    assert not bumped["reached"]
    assert bumped["contact"]["category"] == "wall"
    assert bumped["contact"] == generate_home(SEED).labels()[bumped["contact"]["id"]]
    bx, by, byaw = bumped["base_pose"]
    assert byaw == pytest.approx(1.0)
    gap = min(point_rect_distance(bx, by, w.footprint) for w in home.walls)
    assert ROBOT_RADIUS - 0.005 < gap < ROBOT_RADIUS + 0.06
    assert bumped["travelled_m"] == pytest.approx(math.dist(ahead, (bx, by)), abs=1e-6)


def _clear_heading(home, x: float, y: float) -> float:
    """A heading from (x, y) whose robot-wide corridor to the outline meets nothing but walls."""
    pieces = [f.footprint for f in home.furniture] + [o.footprint for o in home.objects]
    for degrees in range(0, 360, 5):
        heading = math.radians(degrees)
        samples = [(x + s * math.cos(heading), y + s * math.sin(heading)) for s in np.arange(0.0, 15.0, 0.02)]
        inside = [(px, py) for px, py in samples if home.room_at(px, py) is not None]
        if all(point_rect_distance(px, py, r) > ROBOT_RADIUS + 0.1 for px, py in inside for r in pieces):
            if clearance(home, inside[0][0] + 0.3 * math.cos(heading), inside[0][1] + 0.3 * math.sin(heading)) > 0.3:
                return heading
    pytest.fail("no clear heading from the start pose")


def test_malformed_commands_name_the_field_and_the_world_keeps_serving(world: World) -> None:
    session, keys = world
    bad = [
        ("observe", {}, "observe: no home yet"),
        ("move_base", {"path": [[0, 0]]}, "move_base: no home yet"),
        ("reset", {}, "reset.seed: missing"),
        ("reset", {"seed": -1}, "reset.seed"),
        ("reset", {"seed": "3"}, "reset.seed: expected an integer"),
        ("reset", {"seed": 1, "n_rooms": 12}, "reset.n_rooms"),
        ("reset", {"seed": 1, "colour": "red"}, "reset.colour: unknown field"),
    ]
    for verb, meta, message in bad:
        with pytest.raises(QueryFailed, match=message):
            _cmd(world, verb, meta)
    _cmd(world, "reset", {"seed": 1})
    for meta, message in [
        ({}, r"move_base.path: missing"),
        ({"path": []}, r"move_base.path: has 0 waypoints"),
        ({"path": [[0, 0], [1, 1], [2, 2], [1, "a"]]}, r"move_base.path\[3\]: expected \[x, y\] of finite numbers"),
        ({"path": [[0, 0]], "yaw": "north"}, r"move_base.yaw"),
        ({"path": [[0, 0]] * 501}, r"move_base.path: has 501 waypoints"),
    ]:
        with pytest.raises(QueryFailed, match=message):
            _cmd(world, "move_base", meta)
    nan_reply = _raw_query(session, keys.world_cmd("move_base"), b'{"path":[[NaN,1.0]],"arrays":[]}')
    assert nan_reply["ok"] is False and "move_base.path[0]" in nan_reply["error"]
    assert _cmd(world, "observe").meta["observation"] == 1


def _raw_query(session: zenoh.Session, key: str, header: bytes) -> dict:
    """Send a hand-made message (JSON a Python client would refuse to write) and decode the reply."""
    payload = struct.pack(">4sI", b"HBW1", len(header)) + header
    replies = list(session.get(key, payload=payload, timeout=10.0))
    assert len(replies) == 1 and replies[0].ok is not None
    return decode(replies[0].ok.payload.to_bytes()).meta


def test_description_gives_robot_camera_and_urdf(world: World) -> None:
    session, keys = world
    reply = call(session, keys.world_description, {}, timeout_s=10.0).meta
    assert reply["robot"] == {"radius": ROBOT_RADIUS, "height": pytest.approx(1.4)}
    assert reply["camera"]["mount_height_m"] == 1.5 and reply["camera"]["pitch_deg"] == -20.0
    assert {"width", "height", "fx", "fy", "cx", "cy", "hfov_deg", "near", "far"} <= set(reply["camera"])
    links = {link.get("name") for link in ET.fromstring(reply["urdf"]).iter("link")}
    assert {"base_link", "head_camera_link", "head_camera_optical_frame"} <= links


@contextmanager
def _world_thread(seed: int) -> Iterator[tuple[zenoh.Session, Keys, LivenessWatch, threading.Event, threading.Thread]]:
    """A world reset to ``seed`` at start, to be served by the thread given (not yet started) until
    the event is set; a client session connected to it, and a watch on its token."""
    endpoint = free_tcp_endpoint()
    keys = Keys(f"homebot/test-{uuid.uuid4().hex[:8]}")
    server_session, client = open_session(listen=[endpoint]), open_session(connect=[endpoint])
    watch = LivenessWatch(client, keys.world_alive)
    stop = threading.Event()
    server = WorldServer(server_session, keys.namespace, CameraConfig(width=64, height=48))
    thread = threading.Thread(target=server.serve, args=(stop, seed), daemon=True)
    try:
        yield client, keys, watch, stop, thread
    finally:
        stop.set()
        if thread.ident is not None:
            thread.join(10.0)
        watch.close()
        client.close()
        server_session.close()


def test_liveliness_token_comes_and_goes_with_the_server() -> None:
    with _world_thread(2) as (client, keys, watch, stop, thread):
        assert not watch.alive
        thread.start()
        assert watch.wait_alive(10.0)
        frame = call(client, keys.world_cmd("observe"), {}, timeout_s=10.0)
        assert frame.arrays["rgb"].shape == (48, 64, 3)
        stop.set()
        thread.join(10.0)
        assert not thread.is_alive()
        for _ in range(500):
            if watch.gone():
                break
            threading.Event().wait(0.01)
        assert watch.gone() and "liveliness token" in watch.gone()


def test_a_world_reset_at_start_answers_the_first_reset_to_it_without_building_again(
        caplog: pytest.LogCaptureFixture) -> None:
    """The home built at start (``serve(stop, seed)``) answers a first reset to just that seed; once
    another command came, a reset builds the home again, and replies as the first did."""
    def builds() -> int:
        return sum(record.name == "worlds.sim" and record.getMessage().startswith("home 2:")
                   for record in caplog.records)

    caplog.set_level("INFO", logger="worlds.sim")
    with _world_thread(2) as (client, keys, watch, _, thread):
        thread.start()
        assert watch.wait_alive(30.0)
        assert builds() == 1
        first = call(client, keys.world_cmd("reset"), {"seed": 2}, timeout_s=30.0)
        assert builds() == 1
        call(client, keys.world_cmd("observe"), {}, timeout_s=10.0)
        again = call(client, keys.world_cmd("reset"), {"seed": 2}, timeout_s=30.0)
        assert builds() == 2
        assert again.meta == first.meta


def test_standalone_process_serves_and_stops_on_sigterm() -> None:
    endpoint = free_tcp_endpoint()
    keys = Keys(f"homebot/test-{uuid.uuid4().hex[:8]}")
    process = subprocess.Popen(
        [sys.executable, "-m", "worlds.server", "--namespace", keys.namespace, "--listen", endpoint, "--seed", "4",
         "--width", "80", "--height", "60"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    client = open_session(connect=[endpoint])
    watch = LivenessWatch(client, keys.world_alive)
    try:
        assert watch.wait_alive(30.0), process.stderr.read1().decode() if process.poll() is not None else "no token"
        frame = call(client, keys.world_cmd("observe"), {}, timeout_s=10.0)
        assert frame.arrays["depth"].shape == (60, 80)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=15.0) == 0
        assert b"stopped" in process.stderr.read()
    finally:
        if process.poll() is None:
            process.kill()
        watch.close()
        client.close()


def test_camera_options_are_validated_by_the_command_line() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "worlds.server", "--hfov", "200"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 2 and "camera.hfov_deg" in result.stderr


def test_reset_builds_a_given_scene_and_scenario(world: World) -> None:
    home = generate_home(11)
    scenario = make_scenario(home, 11, hidden=True)
    reply = _cmd(world, "reset", {"seed": 0, "scene": dump_spec(home), "scenario": scenario.to_dict()}).meta
    assert reply["scenario"] == scenario.to_dict()
    assert reply["home"]["area_m2"] == pytest.approx(home.area_m2)
    assert reply["base_pose"][:2] == pytest.approx(list(scenario.start_pose[:2]), abs=1e-6)


def test_reset_rejects_a_bad_scene_or_scenario_naming_the_field(world: World) -> None:
    home = generate_home(11)
    spec = dump_spec(home)
    spec["objects"][0]["parent"] = 99999
    with pytest.raises(QueryFailed, match=r"reset\.scene\.objects\[0\]\.parent"):
        _cmd(world, "reset", {"seed": 0, "scene": spec})
    scenario = make_scenario(home, 11).to_dict()
    scenario["answer"] = "E"
    with pytest.raises(QueryFailed, match=r"reset\.scenario\.answer"):
        _cmd(world, "reset", {"seed": 0, "scenario": scenario})
    del scenario["budget"]
    with pytest.raises(QueryFailed, match=r"reset\.scenario\.budget: missing"):
        _cmd(world, "reset", {"seed": 0, "scenario": scenario})
    assert _cmd(world, "reset", {"seed": 11}).meta["scenario"]["seed"] == 11
