"""The scene commands (new, show, check) and the world benchmark, run for real."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from worlds.home import generate_home
from worlds.scene_cli import bench_world, main
from worlds.spec import dump_spec, read_spec_file

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_new_writes_a_spec_that_checks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "home.json"
    assert main(["new", "--seed", "4", "--rooms", "6", "--area", "140", "--out", str(out)]) == 0
    home = read_spec_file(out)
    assert home == generate_home(4, 6, 140.0) and len(home.rooms) == 6
    assert "6 rooms" in capsys.readouterr().err
    assert main(["check", str(out)]) == 0
    line = capsys.readouterr().out
    assert line.count("\n") == 1 and "ok" in line and "6 rooms" in line


def test_new_without_out_prints_the_spec(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["new", "--seed", "2"]) == 0
    assert json.loads(capsys.readouterr().out) == dump_spec(generate_home(2))


def test_bad_arguments_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["new", "--seed", "1", "--rooms", "12"]) == 2
    assert "n_rooms" in capsys.readouterr().err
    assert main(["new"]) == 2
    assert main(["frobnicate"]) == 2


def test_check_reports_the_problems_and_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = dump_spec(generate_home(3, 5, 90.0))
    spec["version"] = 1
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(spec))
    assert main(["check", str(broken)]) == 1
    assert "version: 1 is not supported (expected 2)" in capsys.readouterr().err
    garbled = tmp_path / "garbled.json"
    garbled.write_text("{not json")
    assert main(["check", str(garbled)]) == 1
    assert "garbled.json: not valid JSON" in capsys.readouterr().err
    assert main(["check", str(tmp_path / "missing.json")]) == 1


def test_show_draws_a_png_the_size_of_the_home(tmp_path: Path) -> None:
    small, large = tmp_path / "small.json", tmp_path / "large.json"
    small.write_text(json.dumps(dump_spec(generate_home(1, 4, 60.0))))
    large.write_text(json.dumps(dump_spec(generate_home(1, 10, 300.0))))
    picture = tmp_path / "pictures" / "large.png"
    picture.parent.mkdir()
    assert main(["show", str(large), "--out", str(picture)]) == 0
    assert main(["show", str(small)]) == 0  # next to the spec by default
    large_size, small_size = _png_size(picture), _png_size(small.with_suffix(".png"))
    assert min(small_size) > 600 and large_size[0] * large_size[1] > 2 * small_size[0] * small_size[1]
    assert picture.stat().st_size > 50_000


def test_bench_world_measures_each_area() -> None:
    result = bench_world(areas=(60.0, 120.0), repeats=1)
    assert result["camera"] == "320x240" and set(result["areas"]) == {"60", "120"}
    for row in result["areas"].values():
        assert row["generate_s"] > 0 and row["build_s"] > 0 and row["render_fps"] > 1
        assert row["objects"] > 0 and row["rooms"] >= 4
