"""No Zenoh shared memory by default: a process that sent large messages and was killed left a
16 MB segment per session in /dev/shm, memory that came back only with a reboot, and a long
evaluation ran out of it. A Zenoh configuration file may still turn it on."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from worlds.bus.session import free_tcp_endpoint, open_session, session_config

ROOT = Path(__file__).resolve().parents[1]

#: A peer that sends five 200 kB messages (Zenoh uses shared memory from 3 kB), says so, and waits.
SENDER = """
import sys, time
sys.path.insert(0, {root!r})
from worlds.bus.session import open_session
session = open_session(listen=[{endpoint!r}])
time.sleep(1.5)
for _ in range(5):
    session.put("homebot/shm-test/frame", b"x" * 200_000)
    time.sleep(0.2)
print("sent", flush=True)
time.sleep(60)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/<pid>/maps")
def test_a_peer_killed_after_sending_large_messages_leaves_no_shared_memory_behind() -> None:
    endpoint = free_tcp_endpoint()
    sender = subprocess.Popen([sys.executable, "-c", SENDER.format(root=str(ROOT), endpoint=endpoint)],
                              stdout=subprocess.PIPE, text=True)
    receiver = open_session(connect=[endpoint])
    sizes: list[int] = []
    try:
        receiver.declare_subscriber("homebot/shm-test/frame", lambda sample: sizes.append(len(sample.payload.to_bytes())))
        assert sender.stdout is not None and sender.stdout.readline().strip() == "sent"
        deadline = time.monotonic() + 5.0
        while not sizes and time.monotonic() < deadline:
            time.sleep(0.05)
        assert sizes and sizes[0] == 200_000  # the messages went through
        maps = Path(f"/proc/{sender.pid}/maps").read_text()
        segments = {line.split()[-1] for line in maps.splitlines() if "/dev/shm/" in line}
        assert segments == set()  # nothing a kill could leave behind
    finally:
        sender.send_signal(signal.SIGKILL)
        sender.wait()
        receiver.close()


def test_shared_memory_is_off_unless_a_zenoh_file_turns_it_on(tmp_path: Path) -> None:
    config, _ = session_config(["tcp/127.0.0.1:7000"], [])
    assert config.get_json("transport/shared_memory/enabled") == "false"
    own = tmp_path / "shm.json5"
    own.write_text("{ transport: { shared_memory: { enabled: true } } }")
    config, _ = session_config(["tcp/127.0.0.1:7000"], [], own)
    assert config.get_json("transport/shared_memory/enabled") == "true"
