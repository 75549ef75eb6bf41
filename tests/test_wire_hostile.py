"""A hostile client against a real world over real Zenoh on loopback: every malformed request is
refused with an error naming its field, nothing crashes or hangs, refusals are one rate-limited log
line each, every reply names its world, and ``description`` answers while a long command runs."""

from __future__ import annotations

import copy
import logging
import struct
import threading
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
import zenoh

from agent.app.bench.fuzz import WARM_UP, bench_fuzz, classify, format_fuzz_report
from worlds.bus.codec import MAGIC, Message, decode, encode
from worlds.bus.keys import Keys
from worlds.bus.liveness import LivenessWatch
from worlds.bus.rejections import RejectionLog
from worlds.bus.rpc import CommandServer, PendingReply, QueryFailed, call
from worlds.bus.session import free_tcp_endpoint, open_session
from worlds.home import generate_home
from worlds.robot import CameraConfig
from worlds.robot_arm import arm_spec
from worlds.scenario import make_scenario
from worlds.server import WorldServer
from worlds.spec import dump_spec, load_spec

World = tuple[zenoh.Session, Keys]
VERBS = ("reset", "observe", "move_base", "arm_state", "arm_trajectory", "gripper", "episode_report", "description")


def _key(keys: Keys, verb: str) -> str:
    return keys.world_description if verb == "description" else keys.world_cmd(verb)


def _ask(session: zenoh.Session, key: str, payload: bytes | None) -> tuple[str, dict]:
    """Send ``payload`` as it is (None: no payload); the reply's key and header."""
    replies = [reply for reply in session.get(key, payload=payload, timeout=30.0)]
    assert len(replies) == 1 and replies[0].ok is not None, replies
    return str(replies[0].ok.key_expr), decode(replies[0].ok.payload.to_bytes()).meta


def _refusal(world: World, verb: str, payload: bytes | None) -> str:
    session, keys = world
    _, meta = _ask(session, _key(keys, verb), payload)
    assert meta["ok"] is False and not meta["error"].startswith("internal error"), meta
    return meta["error"]


def _raw(header: bytes, payload: bytes = b"") -> bytes:
    return struct.pack(">4sI", MAGIC, len(header)) + header + payload


def _reset(world: World, seed: int = 0) -> dict:
    session, keys = world
    return call(session, keys.world_cmd("reset"), {"seed": seed}, timeout_s=60.0).meta


@pytest.mark.parametrize("depth", [1_000, 100_000])
def test_a_header_nested_too_deeply_is_refused_naming_the_header(world: World, depth: int) -> None:
    payload = _raw(b'{"seed":' + b"[" * depth + b"]" * depth + b"}")
    assert _refusal(world, "reset", payload).startswith("header: nested deeper than 64 levels")


@pytest.mark.parametrize(("verb", "header", "field"), [
    ("reset", b'{"seed": %s}', "reset.seed"),
    ("move_base", b'{"path": [[%s, 1.0]]}', r"move_base.path[0][0]"),
    ("move_base", b'{"path": [[1.0, 1.0]], "yaw": %s}', "move_base.yaw"),
    ("arm_trajectory", b'{"dt": %s}', "arm_trajectory.dt"),
    ("reset", b'{"seed": 1, "n_rooms": %s}', "reset.n_rooms"),
    ("gripper", b'{"action": %s}', "gripper.action"),
])
@pytest.mark.parametrize("digits", [400, 5_000])
def test_an_integer_of_hundreds_or_thousands_of_digits_is_refused_naming_its_field(
        world: World, verb: str, header: bytes, field: str, digits: int) -> None:
    _reset(world)
    error = _refusal(world, verb, _raw(header % (b"9" * digits)))
    assert error.startswith(f"{field}: the integer") and f"({digits} digits) is outside the 64-bit range" in error


def test_numbers_beyond_their_bounds_are_refused_naming_the_field(world: World) -> None:
    _reset(world)
    for verb, meta, start in [
        ("move_base", {"path": [[1.0, 1.0]], "yaw": 2**63}, "move_base.yaw: expected a finite number"),
        ("move_base", {"path": [[1e300, 1.0]]}, "move_base.path[0]: coordinates must lie within"),
        ("arm_trajectory", {"dt": 1e300}, "arm_trajectory.dt: 1e+300 must be a number"),
        ("reset", {"seed": 2**64 - 1}, "reset.seed: 18446744073709551615 must lie in 0.."),
    ]:
        assert _refusal(world, verb, encode(meta)).startswith(start), (verb, meta)


@pytest.mark.parametrize("verb", VERBS)
def test_an_unknown_array_is_refused_on_every_command(world: World, verb: str) -> None:
    _reset(world)
    meta = {"seed": 0} if verb == "reset" else {"dt": 0.02} if verb == "arm_trajectory" else \
        {"action": "open"} if verb == "gripper" else {"path": [[1.0, 1.0]]} if verb == "move_base" else {}
    arrays = {"junk": np.zeros(1000, np.uint8)}
    if verb == "arm_trajectory":
        arrays["samples"] = np.array([arm_spec().stowed])
    error = _refusal(world, verb, encode(meta, arrays))
    assert error.startswith(f"{verb}.arrays.junk: unknown array"), error


def test_a_zero_length_payload_is_an_empty_request_as_no_payload_is(world: World) -> None:
    session, keys = world
    _reset(world)
    for payload in (None, b""):
        _, meta = _ask(session, keys.world_cmd("arm_state"), payload)
        assert meta["ok"] is True and len(meta["positions"]) == 8
        assert _refusal(world, "move_base", payload).startswith("move_base.path: missing")
        assert _refusal(world, "reset", payload).startswith("reset.seed: missing")


def test_a_scenario_is_checked_against_its_home(world: World) -> None:
    home = generate_home(0)
    good = make_scenario(home, 0).to_dict()
    wall = home.walls[0].center
    for change, start in [
        ({"start_pose": [1e6, -1e6, 99.0]}, "reset.scenario.start_pose: [1000000.0, -1000000.0, 99.0] must have x"),
        ({"start_pose": [900.0, 5.0, 0.0]}, "reset.scenario.start_pose: (900, 5) is in none of the home's rooms"),
        ({"start_pose": [wall[0], wall[1] + 0.1, 0.0]}, "reset.scenario.start_pose: ("),
        ({"seed": -1}, "reset.scenario.seed: -1 is not an integer in 0.."),
        ({"budget": 10**9}, "reset.scenario.budget: 1000000000 is not an integer in 1..10000"),
        ({"budget": 10**30}, "reset.scenario.budget: the integer 100000000000…000000 (31 digits)"),
        ({"target": {**good["target"], "shelf": "top"}}, "reset.scenario.target.shelf: unknown slot"),
        ({"target": {**good["target"], "room": 3}}, "reset.scenario.target.room: expected a word or null"),
    ]:
        error = _refusal(world, "reset", encode({"seed": 0, "scenario": {**good, **change}}))
        assert error.startswith(start), (change, error)
    assert "robot needs 0.25 m" in _refusal(world, "reset", encode(
        {"seed": 0, "scenario": {**good, "start_pose": [wall[0], wall[1] + 0.1, 0.0]}}))
    assert _reset(world)["scenario"] == good  # and the world goes on serving


def test_a_scene_with_unbounded_numbers_is_refused_naming_each_field(world: World) -> None:
    spec = dump_spec(generate_home(0))
    for change, start in [
        (lambda s: s["walls"][0]["center"].__setitem__(0, 1e308), "reset.scene.walls[0].center[0]: 1e+308 is beyond"),
        (lambda s: s["walls"][1]["size"].__setitem__(0, 2e9), "reset.scene.walls[1].size[0]: 2000000000.0 is beyond"),
        (lambda s: s["doorways"][0].__setitem__("width", 1e308), "reset.scene.doorways[0].width: 1e+308 is beyond"),
        (lambda s: s["rooms"][0]["rect"].__setitem__(2, 99999.0), "reset.scene.rooms[0].rect[2]: 99999.0 is beyond"),
        (lambda s: s["rooms"][0]["rect"].__setitem__(3, 999.0), "reset.scene.rooms: their outline"),
        (lambda s: s["walls"].extend([s["walls"][0]] * 1024), "reset.scene.walls: "),
        (lambda s: s["furniture"][0].__setitem__("id", 2**40), "reset.scene.furniture[0].id: 1099511627776 must be"),
    ]:
        bad = copy.deepcopy(spec)
        change(bad)
        error = _refusal(world, "reset", encode({"seed": 0, "scene": bad}))
        assert error.startswith(start), error
    piece = next(i for i, f in enumerate(spec["furniture"]) if f["storage"])
    spec["furniture"][piece]["storage"]["parts"][0]["name"] = 'door"/><link name="x'
    assert _refusal(world, "reset", encode({"seed": 0, "scene": spec})).startswith(
        f"reset.scene.furniture[{piece}].storage.parts[0].name: ")


def test_every_reply_names_the_world_that_answered_a_wildcard_query() -> None:
    with _worlds(2) as (client, keys):
        replies = list(client.get("homebot/**/world/robot/description", timeout=30.0))
        answered = {str(reply.ok.key_expr): decode(reply.ok.payload.to_bytes()).meta for reply in replies}
        assert {key: meta["namespace"] for key, meta in answered.items()} == {
            k.world_description: k.namespace for k in keys}
        refusals = [decode(r.ok.payload.to_bytes()).meta for r in client.get("homebot/**/world/cmd/observe",
                                                                             payload=encode({"x": 1}), timeout=30.0)]
        assert sorted(meta["namespace"] for meta in refusals) == sorted(k.namespace for k in keys)
        assert all(meta["error"] == "observe.x: unknown field (expected camera)" for meta in refusals)


def test_description_answers_while_a_long_reset_runs() -> None:
    with _worlds(1) as (client, (keys,)):
        scene = _big_scene()
        reset = PendingReply(client, keys.world_cmd("reset"), {"seed": 3, "scene": scene}, timeout_s=120.0)
        description = call(client, keys.world_description, {}, timeout_s=30.0)
        assert reset.poll() is None, "the reset was over before the description came"
        assert description.meta["ok"] and "urdf" in description.meta
        assert reset.wait().meta["home"]["area_m2"] == pytest.approx(load_spec(scene).area_m2)


def test_refusals_are_one_line_each_rate_limited_and_all_counted(world: World,
                                                                   caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="worlds.bus.rpc")
    sent = 300
    for index in range(sent):
        assert _refusal(world, "observe", encode({"camera": f"eye{index}"})).startswith("observe.camera:")
    counted = 0
    for _ in range(200):  # the count of lines held back comes once the server is idle
        records = [r for r in caplog.records if r.name == "worlds.bus.rpc"]
        lines = [r for r in records if r.getMessage().startswith("rejected ")]
        counted = len(lines) + sum(int(r.getMessage().split()[0]) for r in records if "not logged" in r.getMessage())
        if counted == sent:
            break
        time.sleep(0.05)
    assert counted == sent
    assert len(lines) < sent  # held back beyond the rate
    assert all(r.exc_info is None and "\n" not in r.getMessage() for r in records)


def test_a_request_beyond_the_queue_is_answered_busy_at_once() -> None:
    """While a command runs and the queue holds as many as it may, one more is told ``busy`` at
    once; the ones held are answered when the command is done."""
    endpoint = free_tcp_endpoint()
    server_session, client = open_session(listen=[endpoint]), open_session(connect=[endpoint])
    entered, release, stop = threading.Event(), threading.Event(), threading.Event()

    def slow(_: Message) -> tuple[dict, dict]:
        entered.set()
        release.wait(30.0)
        return {}, {}

    server = CommandServer(server_session, "test/busy", max_waiting=1)
    server.add("test/busy/cmd", slow)
    thread = threading.Thread(target=server.serve, args=(stop,), daemon=True)
    thread.start()
    try:
        time.sleep(0.3)  # the queryable's declaration reaches the client
        first = PendingReply(client, "test/busy/cmd", timeout_s=30.0)
        assert entered.wait(30.0)
        held = [PendingReply(client, "test/busy/cmd", timeout_s=30.0) for _ in range(2)]
        refused: list[str] = []
        deadline = time.monotonic() + 30.0
        while not refused and time.monotonic() < deadline:  # before the command is done
            for pending in list(held):
                try:
                    pending.poll()
                except QueryFailed as error:
                    refused.append(str(error))
                    held.remove(pending)
            time.sleep(0.01)
        assert refused == ["test/busy/cmd: busy: the world's queue is full (1 waiting); try again later"]
        release.set()
        assert first.wait().meta == {"ok": True, "namespace": "test/busy"}
        assert [pending.wait().meta["ok"] for pending in held] == [True]
    finally:
        release.set()
        stop.set()
        thread.join(10.0)
        server.close()
        client.close()
        server_session.close()


def test_the_rejection_log_writes_a_few_lines_a_second_and_one_traceback_per_place(
        caplog: pytest.LogCaptureFixture) -> None:
    now = [0.0]
    rejections = RejectionLog(logging.getLogger("test.rejections"), per_second=10.0, burst=5, clock=lambda: now[0])
    caplog.set_level(logging.INFO, logger="test.rejections")
    for index in range(50):
        rejections.rejected("k", f"reason {index}")
    assert [r.getMessage() for r in caplog.records] == [f"rejected k: reason {i}" for i in range(5)]
    assert rejections.suppressed == 45
    now[0] = 1.0
    rejections.flush()
    assert caplog.records[-1].getMessage().startswith("45 more refused requests not logged in the last 1.0 s")
    for _ in range(3):
        try:
            raise ZeroDivisionError("a bug")
        except ZeroDivisionError as error:
            rejections.failed("k", error)
    failures = [r for r in caplog.records if r.levelno == logging.ERROR]
    assert [r.exc_info is not None for r in failures] == [True, False, False]
    assert all(r.getMessage() == "internal error answering k: ZeroDivisionError: a bug" for r in failures)


def test_a_fuzz_run_crashes_nothing_hangs_nothing_and_every_refusal_names_its_field() -> None:
    report = bench_fuzz(400, seed=1)
    assert (report["crashes"], report["hangs"], report["failed_health_checks"]) == (0, 0, 0)
    assert report["outcomes"]["named"] == 400, report["examples"]
    assert report["log"]["tracebacks"] == 0
    assert report["log"]["rejection_lines"] + report["log"]["rejections_counted_not_logged"] <= 400


def _fuzz_report(memory: list[tuple[int, float, float]]) -> dict:
    return {"sent": memory[-1][0], "messages": memory[-1][0], "seed": 0, "seconds": 1.0, "per_second": 1.0,
            "by_kind": {}, "outcomes": {o: 0 for o in ("named", "unnamed", "internal", "busy", "accepted", "hang")},
            "crashes": 0, "hangs": 0, "failed_health_checks": 0, "examples": {},
            "memory": [{"sent": n, "rss_mib": rss, "peak_mib": rss, "anon_mib": own} for n, rss, own in memory],
            "log": {"bytes": 0, "lines": 0, "tracebacks": 0, "rejection_lines": 0, "rejections_counted_not_logged": 0}}


def test_the_fuzz_memory_target_is_judged_from_after_the_warm_up_on_the_larger_growth() -> None:
    def target(memory: list[tuple[int, float, float]]) -> str:
        return next(line for line in format_fuzz_report(_fuzz_report(memory)).splitlines() if line.startswith("target"))

    warm_up_cost = [(0, 100.0, 80.0), (WARM_UP, 130.0, 90.0)]
    assert target(warm_up_cost + [(10 * WARM_UP, 140.0, 95.0)]).endswith("+7.7 % (the larger of RSS and own memory): met")
    assert target(warm_up_cost + [(10 * WARM_UP, 131.0, 100.0)]).endswith("+11.1 % (the larger of RSS and own memory): NOT met")
    assert target([(0, 100.0, 80.0), (500, 101.0, 81.0)]).endswith("n/a (send more than 1000)")


def test_replies_are_sorted_by_what_they_say() -> None:
    assert classify(None) == ("hang", "")
    assert classify(encode({"ok": True})) == ("accepted", "")
    assert classify(encode({"ok": False, "error": "move_base.yaw: bad"}))[0] == "named"
    assert classify(encode({"ok": False, "error": "something went wrong"}))[0] == "unnamed"
    assert classify(encode({"ok": False, "error": "internal error: KeyError: 'x'"}))[0] == "internal"


def _big_scene() -> dict:
    """Home 3 stretched 3.5 times (1,960 m², within the 2,000 allowed): a reset that takes a while."""
    spec, k = dump_spec(generate_home(3)), 3.5
    shift = {}
    for room in spec["rooms"]:
        shift[room["name"]] = ((k - 1) * room["rect"][0], (k - 1) * room["rect"][1])
        room["rect"] = [k * v for v in room["rect"]]
    for wall in spec["walls"]:
        (cx, cy, cz), (sx, sy, sz) = wall["center"], wall["size"]
        wall["center"], wall["size"] = [k * cx, k * cy, cz], [sx * k if sx > sy else sx, sy * k if sy > sx else sy, sz]
    for door in spec["doorways"]:
        door["center"] = [k * v for v in door["center"]]
    for thing in spec["furniture"] + spec["objects"]:
        dx, dy = shift[thing["room"]]
        thing["center"] = [thing["center"][0] + dx, thing["center"][1] + dy, thing["center"][2]]
    return spec


@contextmanager
def _worlds(count: int) -> Iterator[tuple[zenoh.Session, list[Keys]]]:
    """``count`` worlds, each on its own session and namespace, and one client connected to all."""
    endpoints = [free_tcp_endpoint() for _ in range(count)]
    keys = [Keys(f"homebot/hostile-{uuid.uuid4().hex[:8]}") for _ in range(count)]
    sessions = [open_session(listen=[endpoint]) for endpoint in endpoints]
    client = open_session(connect=endpoints)
    stop = threading.Event()
    threads = [threading.Thread(target=WorldServer(session, k.namespace, CameraConfig(64, 48)).serve, args=(stop,),
                                daemon=True) for session, k in zip(sessions, keys)]
    watches = [LivenessWatch(client, k.world_alive) for k in keys]
    try:
        for thread in threads:
            thread.start()
        assert all(watch.wait_alive(30.0) for watch in watches)
        yield client, keys
    finally:
        stop.set()
        for thread in threads:
            thread.join(10.0)
        for watch in watches:
            watch.close()
        client.close()
        for session in sessions:
            session.close()
