"""`homebot bench step`: the report's figures from known stage samples, and its shape after a real run."""

from __future__ import annotations

import json

import pytest

from agent.app.bench.step import MemoryTimer, episode_report, format_step_report, step_targets
from agent.app.cli import main
from agent.timing import StageTimer
from worlds.bus.session import free_tcp_endpoint


def _timer(steps: int, tsdf: list[float]) -> StageTimer:
    """Each step: render 20 ms, transport 5, planning 10, VLM 8 and 2, drive 4; its map stage from ``tsdf``."""
    timer = StageTimer()
    for step in range(steps):
        for stage, ms in (("render", 20.0), ("transport", 5.0), ("tsdf", tsdf[step]), ("vlm", 8.0),
                          ("vlm_directions", 2.0), ("planning", 10.0), ("drive", 4.0), ("tick", 1.0)):
            timer.record(stage, ms)
    return timer


def test_the_overhead_is_the_wall_time_less_render_drive_and_vlm_split_into_its_stages() -> None:
    tsdf = [30.0] * 50
    result = {"steps": 50, "seconds": 50 * 0.1, "status": "answered", "ticks": 500}  # 100 ms per step
    report = episode_report(_timer(50, tsdf), result, [])
    overhead = report["overhead"]
    assert overhead["render_per_step_ms"] == pytest.approx(20.0)
    assert overhead["vlm_per_step_ms"] == pytest.approx(10.0)  # both VLM stages
    assert overhead["drive_per_step_ms"] == pytest.approx(4.0)
    assert overhead["per_step_ms"] == pytest.approx(66.0)  # 100 - 20 - 10 - 4
    assert overhead["parts_per_step_ms"] == pytest.approx({"transport": 5.0, "tsdf": 30.0, "planning": 10.0,
                                                           "the rest": 21.0})
    assert overhead["over_render"] == pytest.approx(3.3)
    assert report["per_step_ms"] == pytest.approx(100.0)
    assert report["startup_s"] is None
    assert report["memory"]["end_over_step"] is None  # no samples


def test_the_map_stage_compares_steps_35_to_44_with_steps_3_to_7_in_order() -> None:
    tsdf = [1000.0, 1000.0, 10.0, 12.0, 11.0, 13.0, 9.0] + [50.0] * 27 + [20.0 + k for k in range(10)] + [999.0]
    assert len(tsdf) == 45
    report = episode_report(_timer(45, tsdf), {"steps": 45, "seconds": 9.0, "status": "answered", "ticks": 90}, [])
    assert report["tsdf_ms"] == tsdf
    assert report["map_stage"] == pytest.approx({"early_ms": 11.0, "late_ms": 24.5, "late_over_early": 24.5 / 11.0})
    short = episode_report(_timer(43, tsdf), {"steps": 43, "seconds": 9.0, "status": "answered", "ticks": 90}, [])
    assert short["map_stage"]["early_ms"] == 11.0 and short["map_stage"]["late_over_early"] is None


def test_memory_samples_are_taken_as_each_frame_is_fused() -> None:
    timer = MemoryTimer()
    for _ in range(3):
        timer.record("render", 1.0)
        timer.record("tsdf", 1.0)
    assert len(timer.rss_mb) == 3 and all(mb > 0 for mb in timer.rss_mb)
    rss = [100.0] * 9 + [200.0] + [210.0] * 5
    report = episode_report(_timer(15, [1.0] * 15), {"steps": 15, "seconds": 3.0, "status": "answered", "ticks": 30},
                            rss)
    assert report["memory"] == pytest.approx({"step_10_mb": 200.0, "end_mb": 210.0, "end_over_step": 1.05})


def _episode(area: float, per_step_s: float, render_ms: float, tsdf: list[float], rss: list[float],
             startup_s: float | None) -> dict:
    steps = len(tsdf)
    timer = _timer(steps, tsdf)
    timer.samples["render"] = [render_ms] * steps
    result = {"steps": steps, "seconds": steps * per_step_s, "status": "answered", "ticks": 10 * steps}
    if startup_s is not None:
        result["startup_s"] = startup_s
    return {**episode_report(timer, result, rss), "area_m2": area, "floor_m2": area, "rooms": 4, "snapshot_bytes": 1}


def test_each_target_has_its_goal_its_values_and_whether_they_meet_it() -> None:
    small = _episode(60.0, 0.1, 20.0, [10.0] * 22, [100.0] * 22, 2.0)
    big = _episode(300.0, 0.14, 28.0, [10.0] * 7 + [20.0] * 44, [100.0] * 10 + [120.0] * 41, None)
    targets = {t["key"]: t for t in step_targets([small, big])}
    assert targets["per_step"]["values"] == {"300÷60": pytest.approx(1.4)} and targets["per_step"]["met"] is True
    assert targets["render"]["values"] == {"300÷60": pytest.approx(1.4)} and targets["render"]["met"] is False
    assert targets["map_late"]["values"] == {"300 m²": pytest.approx(2.0)} and targets["map_late"]["met"] is False
    assert targets["startup_s"]["values"] == {"60 m²": 2.0, "300 m²": None}
    assert targets["startup_s"]["met"] is True and "startup_s" in targets["startup_s"]["note"]
    assert targets["memory"]["values"] == {"60 m²": pytest.approx(1.0), "300 m²": pytest.approx(1.2)}
    assert targets["memory"]["met"] is False
    assert targets["overhead"]["goal"] == 0.25 and set(targets["overhead"]["values"]) == {"60 m²", "300 m²"}
    text = format_step_report({"seed": 0, "overhead_counts": "…", "episodes": [small, big],
                               "targets": list(targets.values())})
    assert "per-step total 300÷60" in text and "≤ 1.5" in text and "1.40: met" in text
    assert "300 m² 1.20: NOT met" in text
    alone = {t["key"]: t for t in step_targets([small])}
    assert alone["per_step"]["met"] is None and "two homes" in alone["per_step"]["note"]
    assert alone["map_late"]["met"] is None and "22 steps, fewer than 44" in alone["map_late"]["note"]


def test_a_real_run_reports_both_homes_and_every_target(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["bench", "step", "--seed", "0", "--set", "episode.budget=3", "--listen", free_tcp_endpoint(), "--json"])
    assert code == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert [e["area_m2"] for e in report["episodes"]] == [60.0, 300.0]
    assert captured.err.count("done, ") == 2  # a progress line per episode
    for episode in report["episodes"]:
        assert episode["steps"] == 3 and len(episode["tsdf_ms"]) == 3 and len(episode["rss_mb"]) == 3
        assert {"render", "transport", "tsdf", "planning", "vlm", "tick"} <= set(episode["stages"])
        assert episode["overhead"]["over_render"] > 0
    targets = {t["key"]: t for t in report["targets"]}
    assert targets["per_step"]["values"]["300÷60"] > 0 and targets["render"]["values"]["300÷60"] > 0
    assert targets["map_late"]["met"] is None and "3 steps, fewer than 44" in targets["map_late"]["note"]
    assert targets["memory"]["met"] is None


def test_an_area_out_of_range_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "step", "--area", "20"]) == 2
    assert "--area 20 is not in 60..300" in capsys.readouterr().err
