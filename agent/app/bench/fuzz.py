"""`homebot bench fuzz`: malformed requests against a world process, and what they cost it.

A world is started for the run (`WorldProcess`, its log in a file) and reset to a home; then the
malformed requests of `agent.app.bench.fuzz_cases` go to it one after the other. Each reply is
sorted: refused naming a field (what every case must get), refused without a field, an internal
error, a ``busy`` answer, accepted (a malformed request taken for a good one), or none within the
timeout (a hang). Every thousand cases a good request must still be answered. The world's resident
memory is read before, during and after, and its log measured: lines, bytes and tracebacks.

Memory must stay flat over the malformed requests: the target is measured from after the first
thousand (``WARM_UP``), by when the world has run each refusal's code path once and Zenoh has
mapped its shared-memory pool for the large payloads (a one-off cost of about 25 MiB, most of it
mapped files, not growth); the figure from before the first request is printed beside it.
"""

from __future__ import annotations

import re
import tempfile
import time
import uuid
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import zenoh

from agent.app.bench.fuzz_cases import Case, Catalogue
from agent.app.config import CameraSettings
from agent.app.runtime.world_process import WorldProcess
from worlds.bus.codec import WireError, decode
from worlds.bus.keys import Keys
from worlds.bus.link import WorldLink
from worlds.bus.rpc import QueryFailed
from worlds.bus.session import free_tcp_endpoint, open_session
from worlds.home import generate_home
from worlds.spec import dump_spec

OUTCOMES = ("named", "unnamed", "internal", "busy", "accepted", "hang")
_NAMED = re.compile(r"^[A-Za-z_][\w.\[\]\-/]*: \S")
_SUPPRESSED = re.compile(r"(\d+) more refused requests not logged")
_HOME_SEED = 0
_HEALTH_EVERY = 1000
#: Requests after which memory is the baseline of the flatness target (see the module's docstring).
WARM_UP = 1000
#: The most the world's memory may grow from after the warm-up to the end, as a fraction.
MEMORY_GOAL = 0.10


def classify(reply_payload: bytes | None) -> tuple[str, str]:
    """Sort one reply to a malformed request into one of `OUTCOMES` (a hang has no payload).

    Args:
        reply_payload: the reply's bytes, or None when none came.

    Returns:
        The outcome and the reply's error text ("" when there is none).
    """
    if reply_payload is None:
        return "hang", ""
    try:
        meta = decode(reply_payload).meta
    except WireError as error:
        return "unnamed", f"malformed reply: {error}"
    error = str(meta.get("error", ""))
    if meta.get("ok") is True:
        return "accepted", ""
    if error.startswith("internal error"):
        return "internal", error
    if error.startswith("busy"):
        return "busy", error
    return ("named" if _NAMED.match(error) else "unnamed"), error


def _rss_mib(pid: int) -> dict[str, float]:
    """The process's resident memory now, at its peak, and its own part: without the files and shared
    memory it maps (Zenoh maps a same-host peer's shared-memory pool once it sends large messages),
    from Linux's /proc, in MiB."""
    fields = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        name, _, value = line.partition(":")
        if name in ("VmRSS", "VmHWM", "RssAnon"):
            fields[name] = int(value.split()[0]) / 1024
    return {"rss_mib": round(fields.get("VmRSS", 0.0), 1), "peak_mib": round(fields.get("VmHWM", 0.0), 1),
            "anon_mib": round(fields.get("RssAnon", 0.0), 1)}


def _send(session: zenoh.Session, key: str, payload: bytes, timeout_s: float) -> bytes | None:
    for reply in session.get(key, payload=payload, timeout=timeout_s):
        if reply.ok is not None:
            return reply.ok.payload.to_bytes()
    return None


def _log_figures(path: Path) -> dict[str, Any]:
    text = path.read_text(errors="replace")
    lines = text.splitlines()
    return {
        "bytes": len(text.encode()),
        "lines": len(lines),
        "tracebacks": sum(line.startswith("Traceback") for line in lines),
        "rejection_lines": sum(" rejected " in line for line in lines),
        "rejections_counted_not_logged": sum(int(m.group(1)) for m in _SUPPRESSED.finditer(text)),
    }


def bench_fuzz(messages: int, seed: int = 0, timeout_s: float = 30.0,
               progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Send ``messages`` malformed requests to a world started for it; count how each was answered.

    Args:
        messages: how many.
        seed: the cases' seed.
        timeout_s: how long one reply may take before it counts as a hang.
        progress: told a line now and then.

    Returns:
        The report: outcomes by kind, crashes, hangs, the world's memory and its log's size.
    """
    say = progress or (lambda line: None)
    keys = Keys(f"homebot/fuzz-{uuid.uuid4().hex[:8]}")
    endpoint = free_tcp_endpoint()
    with tempfile.TemporaryDirectory(prefix="homebot-fuzz-") as folder:
        log_path = Path(folder) / "world.log"
        world = WorldProcess(keys.namespace, endpoint, CameraSettings(64, 48), log_path)
        session = open_session(connect=[endpoint])
        link = WorldLink(session, keys, timeout_s)
        try:
            world.wait_ready(link, 60.0)
            scenario = link.call("reset", {"seed": _HOME_SEED}, timeout_s=60.0).meta["scenario"]
            home = generate_home(_HOME_SEED)
            cases = Catalogue(home, dump_spec(home), scenario, seed).cases(messages)
            report = _run(session, link, keys, world, cases, messages, timeout_s, say)
        finally:
            link.close()
            session.close()
            world.stop()
        report["log"] = _log_figures(log_path)
    report.update({"messages": messages, "seed": seed, "timeout_s": timeout_s})
    return report


def _run(session: zenoh.Session, link: WorldLink, keys: Keys, world: WorldProcess, cases: Any, messages: int,
         timeout_s: float, say: Callable[[str], None]) -> dict[str, Any]:
    pid = world.process.pid
    by_kind: dict[str, Counter[str]] = {}
    examples: dict[str, str] = {}
    memory = [{"sent": 0, **_rss_mib(pid)}]
    checkpoints = {max(1, messages * k // 10) for k in range(1, 11)} | {min(messages, WARM_UP)}
    unhealthy, crashed, sent = 0, False, 0
    started = last_said = time.monotonic()
    for case in cases:
        key = keys.world_description if case.verb == "description" else keys.world_cmd(case.verb)
        outcome, error = classify(_send(session, key, case.payload, timeout_s))
        sent += 1
        by_kind.setdefault(case.kind, Counter())[outcome] += 1
        if outcome != "named":
            examples.setdefault(f"{case.kind}/{outcome}", error[:200])
        if world.process.poll() is not None:
            crashed = True
            say(f"  fuzz: the world exited with code {world.process.returncode} after {sent} requests")
            break
        if sent % _HEALTH_EVERY == 0:
            unhealthy += not _healthy(link)
        if sent in checkpoints:
            memory.append({"sent": sent, **_rss_mib(pid)})
        if time.monotonic() - last_said > 5.0:
            last_said = time.monotonic()
            hangs = sum(c["hang"] for c in by_kind.values())
            say(f"  fuzz: {sent}/{messages} sent, {hangs} hangs, world RSS {memory[-1]['rss_mib']:.0f} MiB")
    seconds = time.monotonic() - started
    totals = sum(by_kind.values(), Counter())
    return {
        "sent": sent, "seconds": round(seconds, 1), "per_second": round(sent / max(seconds, 1e-9), 1),
        "outcomes": {outcome: totals[outcome] for outcome in OUTCOMES},
        "by_kind": {kind: {o: counts[o] for o in OUTCOMES if counts[o]} for kind, counts in sorted(by_kind.items())},
        "crashes": int(crashed), "hangs": totals["hang"], "failed_health_checks": unhealthy,
        "memory": memory, "examples": examples,
    }


def _growth(before: dict[str, float], after: dict[str, float], key: str) -> str:
    return f"{100 * (after[key] - before[key]) / max(before[key], 1e-9):+.1f} %"


def _memory_target(warm: dict[str, float], last: dict[str, float]) -> str:
    """The flatness target's line: both memory figures' growth after the warm-up, its goal and verdict."""
    if warm["sent"] != WARM_UP or last["sent"] <= WARM_UP:
        return f"target: memory flat after the first {WARM_UP} requests: n/a (send more than {WARM_UP})"
    grown = max((last[key] - warm[key]) / max(warm[key], 1e-9) for key in ("rss_mib", "anon_mib"))
    verdict = "met" if grown <= MEMORY_GOAL else "NOT met"
    return (f"target: memory from request {WARM_UP} to {last['sent']} ≤ +{100 * MEMORY_GOAL:.0f} %: "
            f"{100 * grown:+.1f} % (the larger of RSS and own memory): {verdict}")


def _healthy(link: WorldLink) -> bool:
    try:
        return link.call("arm_state", {}).meta.get("ok") is True
    except QueryFailed:
        return False


def format_fuzz_report(report: dict[str, Any]) -> str:
    """The fuzz report as lines: outcomes by kind, then crashes, hangs, memory and the log.

    Args:
        report: the report of `bench_fuzz`.

    Returns:
        The text.
    """
    lines = [f"bench fuzz: {report['sent']} of {report['messages']} malformed requests (seed {report['seed']}) in "
             f"{report['seconds']:.0f} s, {report['per_second']:.0f} a second",
             f"{'kind':<16}" + "".join(f"{o:>10}" for o in ("sent", *OUTCOMES))]
    for kind, counts in report["by_kind"].items():
        lines.append(f"{kind:<16}{sum(counts.values()):>10}" + "".join(f"{counts.get(o, 0):>10}" for o in OUTCOMES))
    totals = report["outcomes"]
    lines.append(f"{'all':<16}{report['sent']:>10}" + "".join(f"{totals[o]:>10}" for o in OUTCOMES))
    first, last = report["memory"][0], report["memory"][-1]
    warm = next((m for m in report["memory"] if m["sent"] == WARM_UP), first)
    log = report["log"]
    lines += [
        f"crashes {report['crashes']}, hangs {report['hangs']}, failed health checks {report['failed_health_checks']}",
        *(f"world {what}: {first[key]:.0f} MiB before, {warm[key]:.0f} MiB after {warm['sent']} requests, "
          f"{last[key]:.0f} MiB after {last['sent']} ({_growth(first, last, key)} from before, "
          f"{_growth(warm, last, key)} from {warm['sent']})"
          for what, key in (("RSS", "rss_mib"), ("own memory (RSS less mapped files and shared memory)", "anon_mib"))),
        f"world peak RSS {last['peak_mib']:.0f} MiB",
        _memory_target(warm, last),
        f"world log: {log['bytes'] / 1024:.0f} KiB, {log['lines']} lines, {log['tracebacks']} tracebacks, "
        f"{log['rejection_lines']} refusals logged, {log['rejections_counted_not_logged']} counted without a line",
    ]
    lines += [f"  e.g. {where}: {text}" for where, text in sorted(report["examples"].items())]
    return "\n".join(lines)
