"""`homebot bench faults`: how soon, and how, a fault is reported, against real world processes over
Zenoh on loopback.

- ``killed``: a world is killed (SIGKILL) with four queries in flight; seconds until every one of
  them has failed, and the reason of the first.
- ``frozen``: a world is stopped (SIGSTOP) with a query in flight; seconds until it fails, and why
  (its timeout is `FROZEN_TIMEOUT_S`).
- ``closed port``, ``other namespace``: an episode joins an endpoint where nothing listens, or where
  the only world serves under another namespace; seconds from opening its end of the bus to the error.
- ``ctrl-c run``: seconds from Ctrl-C (SIGINT to its process group) to the exit of a `homebot run`
  in the middle of its episode.
"""

from __future__ import annotations

import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from agent.app.config import Config, load_config
from agent.app.runtime.episode_bus import EpisodeBus
from agent.app.runtime.request import RunRequest
from agent.app.runtime.world_process import WorldProcess, WorldStartError
from worlds.bus.keys import Keys
from worlds.bus.link import WorldLink
from worlds.bus.rpc import PendingReply, QueryFailed
from worlds.bus.session import free_tcp_endpoint, open_session

#: The timeout of the query in flight to a frozen world.
FROZEN_TIMEOUT_S = 2.0

Sample = tuple[float, str]


def bench_faults(repeats: int, progress: Callable[[str], None]) -> dict[str, Any]:
    """Each fault ``repeats`` times: the median and the slowest seconds to its report, and its reason.

    Args:
        repeats: how many times each fault is caused.
        progress: called with a line after each one.

    Returns:
        The report.
    """
    config = load_config(overrides=["bus.listen=[]"])
    cases: dict[str, Callable[[Config, Path], Sample]] = {
        "killed": _killed, "frozen": _frozen, "closed port": _closed_port,
        "other namespace": _other_namespace, "ctrl-c run": _ctrl_c_run}
    report: dict[str, Any] = {"repeats": repeats, "frozen_timeout_s": FROZEN_TIMEOUT_S, "faults": {}}
    with tempfile.TemporaryDirectory(prefix="homebot-bench-faults-") as scratch:
        for name, case in cases.items():
            samples = []
            for number in range(repeats):
                samples.append(case(config, Path(scratch) / f"{name.replace(' ', '-')}-{number}"))
                progress(f"  {name} {number + 1}/{repeats}: {samples[-1][0]:.2f} s")
            seconds = [s for s, _ in samples]
            report["faults"][name] = {"median_s": round(statistics.median(seconds), 3),
                                      "max_s": round(max(seconds), 3), "reason": samples[-1][1]}
    return report


def format_faults_table(report: dict[str, Any]) -> str:
    """The faults bench's report as a table: one row per fault.

    Args:
        report: the report.

    Returns:
        The table's text.
    """
    lines = [f"bench faults: seconds to the report, over {report['repeats']} of each "
             f"(a frozen world's query times out after {report['frozen_timeout_s']:g} s)",
             f"{'fault':<16} {'median s':>9} {'max s':>7}  reason"]
    for name, row in report["faults"].items():
        reason = row["reason"].splitlines()[0]
        lines.append(f"{name:<16} {row['median_s']:>9.2f} {row['max_s']:>7.2f}  {reason}")
    return "\n".join(lines)


@contextmanager
def _world(config: Config, folder: Path) -> Iterator[tuple[WorldLink, WorldProcess]]:
    """A world process of seed 0, connected to a session of its own here, reset and ready."""
    endpoint = free_tcp_endpoint()
    session = open_session(listen=[endpoint])
    link = WorldLink(session, Keys("homebot/bench-faults"), config.bus.query_timeout_s)
    world = WorldProcess(link.keys.namespace, free_tcp_endpoint(), config.camera, folder / "world.log", [endpoint], 0)
    link.follow_process(world.process.poll)
    try:
        world.wait_ready(link, config.bus.world_start_timeout_s)
        link.call("reset", {"seed": 0}, timeout_s=config.bus.world_start_timeout_s)
        yield link, world
    finally:
        link.close()
        world.stop()
        session.close()


def _failed(pending: PendingReply) -> str:
    try:
        pending.wait()
    except QueryFailed as error:
        return str(error)
    return "it answered"


def _killed(config: Config, folder: Path) -> Sample:
    with _world(config, folder) as (link, world):
        os.kill(world.process.pid, signal.SIGSTOP)  # so that the queries stay in flight until it is killed
        pending = [link.request("observe", {"camera": "head"}, 60.0), link.request("arm_state", {}, 60.0),
                   link.describe(60.0), link.request("episode_report", {}, 60.0)]
        started = time.monotonic()
        world.process.kill()
        reasons = [_failed(query) for query in pending]
        return time.monotonic() - started, reasons[0]


def _frozen(config: Config, folder: Path) -> Sample:
    with _world(config, folder) as (link, world):
        os.kill(world.process.pid, signal.SIGSTOP)
        started = time.monotonic()
        reason = _failed(link.request("observe", {"camera": "head"}, FROZEN_TIMEOUT_S))
        return time.monotonic() - started, reason


def _join(config: Config, folder: Path, endpoint: str, namespace: str) -> Sample:
    """Seconds from opening an episode's end of the bus that joins ``endpoint`` to its start error."""
    started = time.monotonic()
    bus = EpisodeBus.open(RunRequest(0, config, folder, connect=endpoint, namespace=namespace))
    try:
        bus.wait_ready(config.bus.world_start_timeout_s)
        reason = "a world answered"
    except WorldStartError as error:
        reason = str(error)
    finally:
        bus.close()
    return time.monotonic() - started, reason


def _closed_port(config: Config, folder: Path) -> Sample:
    return _join(config, folder, free_tcp_endpoint(), "homebot/default")


def _other_namespace(config: Config, folder: Path) -> Sample:
    endpoint = free_tcp_endpoint()
    world = WorldProcess("homebot/bench-elsewhere", endpoint, config.camera, folder / "world.log")
    try:
        world.wait_listening(config.bus.world_start_timeout_s)
        return _join(config, folder, endpoint, "homebot/bench-here")
    finally:
        world.stop()


def foreground_sigint() -> None:
    """Popen's ``preexec_fn`` for a command that will get Ctrl-C: SIGINT back to its default, as a
    shell gives a foreground job. A process started in the background by a shell without job
    control (``nohup … &``) ignores SIGINT, and an ignored signal stays ignored across exec: its
    Ctrl-C would do nothing."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _ctrl_c_run(config: Config, folder: Path) -> Sample:
    run = subprocess.Popen([sys.executable, "-m", "agent.app.cli", "run", "--seed", "0", "--out", str(folder),
                            "--listen", free_tcp_endpoint()], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           text=True, start_new_session=True, preexec_fn=foreground_sigint)
    try:
        while not (logs := list(folder.glob("*/snapshots.jsonl"))) or len(logs[0].read_text().splitlines()) < 3:
            if run.poll() is not None:
                return 0.0, f"the run ended before its episode got under way: {run.communicate()[1][-500:]}"
            time.sleep(0.05)
        started = time.monotonic()
        os.killpg(run.pid, signal.SIGINT)
        _, stderr = run.communicate(timeout=120)
        last = stderr.strip().splitlines()[-1:] or ["(nothing on stderr)"]
        return time.monotonic() - started, f"exit code {run.returncode}: {last[0]}"
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGKILL)
            run.wait()
