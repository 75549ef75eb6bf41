"""Across hosts: a world behind TLS with mutual authentication and access control (`--zenoh-config`),
on loopback with certificates made here. A peer with the right certificate runs an episode; one
without a certificate, or with one another authority signed, is refused with the reason; a peer
whose certificate only allows the robot's description cannot reset the world."""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from agent.app.cli import build_parser, main
from tls_pki import make_pki, world_access, zenoh_file
from worlds.bus.keys import Keys
from worlds.bus.link import WorldLink
from worlds.bus.rpc import QueryFailed
from worlds.bus.session import (EndpointError, ZenohConfigError, check_endpoint, free_tcp_endpoint,
                                open_session, session_config, unreached)

NAMESPACE = "homebot/tls-lab"

needs_openssl = pytest.mark.skipif(shutil.which("openssl") is None, reason="no openssl command to make certificates")


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The certificates and a Zenoh configuration file per peer: ``world`` (with access control),
    ``agent``, ``viewer``, ``nocert`` (trusts the authority, shows no certificate) and ``rogue``
    (trusts it, shows a certificate another authority signed)."""
    folder = make_pki(tmp_path_factory.mktemp("pki"))
    zenoh_file(folder, "world", "world", world_access(NAMESPACE))
    for name, cert in (("agent", "agent"), ("viewer", "viewer"), ("nocert", None), ("rogue", "rogue")):
        zenoh_file(folder, name, cert)
    return folder


@pytest.fixture(scope="module")
def tls_world(pki: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """`homebot world` listening on tls/127.0.0.1 with mutual TLS and access control; yields its
    endpoint once a peer with the agent's certificate sees it alive."""
    endpoint = free_tcp_endpoint().replace("tcp/", "tls/")
    log = tmp_path_factory.mktemp("world") / "world.log"
    with open(log, "wb") as out:
        world = subprocess.Popen([sys.executable, "-m", "worlds.server", "--namespace", NAMESPACE, "--listen",
                                  endpoint, "--zenoh-config", str(pki / "world.json5")],
                                 stdout=out, stderr=subprocess.STDOUT)
    try:
        with open_session(connect=[endpoint], zenoh_config=pki / "agent.json5") as session:
            link = WorldLink(session, Keys(NAMESPACE))
            alive = link.liveness.wait_alive(60.0)
            link.close()
        assert alive, log.read_text()
        yield endpoint
    finally:
        world.terminate()
        world.wait(10)


def test_tls_and_quic_endpoints_are_locators() -> None:
    for endpoint in ("tls/127.0.0.1:7447", "tls/lab-host:7447", "quic/10.0.0.2:7447"):
        assert check_endpoint(endpoint) == endpoint


def test_a_zenoh_file_is_the_base_and_its_own_endpoints_win(tmp_path: Path) -> None:
    plain = tmp_path / "plain.json5"
    plain.write_text("{ transport: { link: { tls: { enable_mtls: true } } } }")
    config, listening = session_config(["tcp/127.0.0.1:7000"], ["tls/10.0.0.2:7447"], plain)
    assert listening == ["tcp/127.0.0.1:7000"]
    assert config.get_json("connect/endpoints") == '["tls/10.0.0.2:7447"]'
    assert config.get_json("mode") == '"peer"' and config.get_json("scouting/multicast/enabled") == "false"
    assert config.get_json("transport/link/tls/enable_mtls") == "true"
    own = tmp_path / "own.json5"
    own.write_text('{ listen: { endpoints: ["tls/0.0.0.0:7447"] }, scouting: { multicast: { enabled: true } } }')
    config, listening = session_config(["tcp/127.0.0.1:7000"], [], own)
    assert listening == ["tls/0.0.0.0:7447"]
    assert config.get_json("scouting/multicast/enabled") == "true"


@pytest.mark.parametrize("text, named", [("{ no_such_key: 1 }", "unknown field `no_such_key`"),
                                         ("{ transport: ", "expected")])
def test_a_zenoh_file_zenoh_refuses_is_named(tmp_path: Path, text: str, named: str) -> None:
    path = tmp_path / "bad.json5"
    path.write_text(text)
    with pytest.raises(ZenohConfigError, match=f"(?s)Zenoh config {path}: .*{named}"):
        open_session(zenoh_config=path)
    with pytest.raises(ZenohConfigError, match="no such file"):
        open_session(zenoh_config=tmp_path / "missing.json5")


@pytest.mark.parametrize("command", [["run"], ["watch"], ["inspect"], ["skill", "run", "stow"],
                                     ["calibrate", "--suite", "s.jsonl"], ["eval", "explore", "--suite", "s.jsonl"],
                                     ["eval", "stop", "--suite", "s.jsonl", "--calibration", "c.json"],
                                     ["bench", "step"], ["bench", "soak"]])
def test_every_command_that_opens_a_session_takes_a_zenoh_file(tmp_path: Path, command: list[str],
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    good = tmp_path / "zenoh.json5"
    good.write_text("{}")
    assert build_parser().parse_args([*command, "--zenoh-config", str(good)]).zenoh_config == str(good.resolve())
    with pytest.raises(SystemExit) as exited:
        build_parser().parse_args([*command, "--zenoh-config", str(tmp_path / "missing.json5")])
    assert exited.value.code == 2
    assert f"--zenoh-config: Zenoh config {tmp_path / 'missing.json5'}: no such file" in capsys.readouterr().err


def test_the_world_refuses_a_zenoh_file_it_cannot_use(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["world", "--zenoh-config", str(tmp_path / "missing.json5")])
    assert exited.value.code == 2
    assert "--zenoh-config: Zenoh config" in capsys.readouterr().err


def test_a_zenoh_file_in_the_settings_is_checked_before_any_world_starts(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--set", f"bus.zenoh_config={tmp_path / 'missing.json5'}", "--out", str(tmp_path)]) == 2
    assert "bus.zenoh_config: Zenoh config" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # no run folder: nothing started


@needs_openssl
@pytest.mark.slow
def test_an_agent_with_the_right_certificate_runs_an_episode_over_tls(
        tls_world: str, pki: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", "--connect", tls_world, "--namespace", NAMESPACE, "--zenoh-config", str(pki / "agent.json5"),
                 "--listen", free_tcp_endpoint(), "--set", "episode.budget=1", "--stop", "budget",
                 "--out", str(tmp_path)])
    assert code == 0, capsys.readouterr().err
    assert "answer " in capsys.readouterr().out


@needs_openssl
@pytest.mark.slow
@pytest.mark.parametrize("peer", ["nocert", "rogue"])
def test_a_peer_without_the_right_certificate_is_refused_with_the_reason(
        tls_world: str, pki: Path, tmp_path: Path, peer: str, capsys: pytest.CaptureFixture[str]) -> None:
    with open_session(connect=[tls_world], zenoh_config=pki / f"{peer}.json5") as session:
        link = WorldLink(session, Keys(NAMESPACE), timeout_s=2.0)
        with pytest.raises(QueryFailed):
            link.describe().wait()
        link.close()
        (reason,) = unreached(session, [tls_world])
    assert reason.startswith(f"{tls_world} took the connection but opened no Zenoh session: the TLS handshake failed")
    code = main(["run", "--connect", tls_world, "--namespace", NAMESPACE, "--zenoh-config", str(pki / f"{peer}.json5"),
                 "--listen", free_tcp_endpoint(), "--set", "bus.world_start_timeout_s=2", "--out", str(tmp_path)])
    error = capsys.readouterr().err
    assert code == 1
    assert f"no world answers under '{NAMESPACE}' at {tls_world} within 2 s" in error
    assert f"; {tls_world} took the connection but opened no Zenoh session" in error
    assert "the TLS handshake failed" in error and "Traceback" not in error


@needs_openssl
@pytest.mark.slow
def test_a_certificate_allowed_only_the_description_cannot_reset_the_world(tls_world: str, pki: Path) -> None:
    with open_session(connect=[tls_world], zenoh_config=pki / "viewer.json5") as session:
        link = WorldLink(session, Keys(NAMESPACE), timeout_s=2.0)
        assert link.liveness.wait_alive(10.0)
        assert "urdf" in str(link.describe().wait().meta).lower()
        with pytest.raises(QueryFailed):
            link.call("reset", {"seed": 1})
        link.close()
    with open_session(connect=[tls_world], zenoh_config=pki / "agent.json5") as session:
        link = WorldLink(session, Keys(NAMESPACE), timeout_s=30.0)
        assert "base_pose" in link.call("reset", {"seed": 1}).meta  # the same query, another certificate
        link.close()


def test_a_closed_port_is_connection_refused_and_an_open_one_reached() -> None:
    endpoint = free_tcp_endpoint()
    with open_session(connect=[endpoint]) as session:
        assert unreached(session, [endpoint]) == [f"connection refused at {endpoint}: nothing listens there"]
    with open_session(listen=[endpoint]) as world, open_session(connect=[endpoint]) as agent:
        assert world is not None and unreached(agent, [endpoint]) == []


def test_listening_on_tls_without_a_certificate_says_what_is_missing(tmp_path: Path) -> None:
    empty = tmp_path / "empty.json5"
    empty.write_text("{}")
    endpoint = free_tcp_endpoint().replace("tcp/", "tls/")
    with pytest.raises(EndpointError, match=f"cannot open a Zenoh session .*{empty}.*Missing TLS private key") as error:
        open_session(listen=[endpoint], zenoh_config=empty)
    assert ".rs:" not in str(error.value)
