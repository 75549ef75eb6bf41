"""The typed configuration: defaults, TOML files, key=value overrides, and errors naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from agent.app.config import BusSettings, CameraSettings, Config, ConfigError, EpisodeSettings, load_config, merge
from agent.mapping.occupancy import OccupancyConfig
from agent.mapping.tsdf import TsdfConfig
from agent.planning.frontier_plan import ExploreConfig
from agent.vlm.sim import SimParams


def test_defaults() -> None:
    config = load_config()
    assert config == Config()
    assert config.camera == CameraSettings()
    assert config.bus.listen == ("tcp/127.0.0.1:7450",)
    assert isinstance(config.bus.listen, tuple)
    assert config.map == OccupancyConfig() and config.map.tsdf == TsdfConfig()
    assert config.explore == ExploreConfig()
    assert config.vlm.sim == SimParams()
    assert config.episode == EpisodeSettings()
    assert load_config(None, []) == Config()


def test_override_nested_keys() -> None:
    config = load_config(overrides=["map.tsdf.voxel_size=0.05", "explore.max_step_m=2.5", "vlm.sim.seed=7"])
    assert config.map.tsdf.voxel_size == 0.05
    assert config.explore.max_step_m == 2.5
    assert config.vlm.sim.seed == 7
    # everything else keeps its default
    assert config.map.tsdf.depth_max == TsdfConfig().depth_max
    assert config.map.resolution == OccupancyConfig().resolution
    assert config.camera == CameraSettings()


def test_overrides_apply_in_order_and_leave_defaults_alone() -> None:
    config = load_config(overrides=["camera.width=640", "camera.width=800"])
    assert config.camera.width == 800
    assert Config().camera.width == 320  # the defaults are not mutated


def test_override_tuple_from_json_list() -> None:
    config = load_config(overrides=['bus.listen=["tcp/127.0.0.1:9000", "tcp/127.0.0.1:9001"]'])
    assert config.bus.listen == ("tcp/127.0.0.1:9000", "tcp/127.0.0.1:9001")
    assert isinstance(config.bus.listen, tuple)
    assert load_config(overrides=["bus.listen=[]"]).bus.listen == ()


def test_override_fixed_length_tuple_of_floats() -> None:
    config = load_config(overrides=["map.floor_band=[-0.2, 1]", "vlm.sim.relevance_none=[2, 5.5]"])
    assert config.map.floor_band == (-0.2, 1.0)
    assert all(isinstance(v, float) for v in config.map.floor_band)
    assert config.vlm.sim.relevance_none == (2.0, 5.5)


def test_fixed_length_tuple_rejects_wrong_length() -> None:
    with pytest.raises(ConfigError, match=r"map\.floor_band"):
        load_config(overrides=["map.floor_band=[0.1]"])


def test_tuple_rejects_bare_string_and_wrong_element() -> None:
    with pytest.raises(ConfigError, match=r"config: bus\.listen: expected"):
        load_config(overrides=["bus.listen=tcp/127.0.0.1:9000"])
    with pytest.raises(ConfigError, match=r"bus\.listen\[1\]: expected str, got 5"):
        load_config(overrides=['bus.listen=["tcp/127.0.0.1:9000", 5]'])


def test_ints_become_floats_but_floats_do_not_become_ints() -> None:
    config = load_config(overrides=["camera.hfov_deg=60", "episode.max_seconds=10"])
    assert config.camera.hfov_deg == 60.0 and isinstance(config.camera.hfov_deg, float)
    assert isinstance(config.episode.max_seconds, float)
    config = load_config(overrides=["camera.width=640"])
    assert config.camera.width == 640 and isinstance(config.camera.width, int)
    with pytest.raises(ConfigError, match=r"config: camera\.width: expected int, got 3\.5"):
        load_config(overrides=["camera.width=3.5"])


def test_values_with_spaces_around_equals() -> None:
    assert load_config(overrides=[" camera.height = 480 "]).camera.height == 480


def test_unknown_keys_are_named() -> None:
    with pytest.raises(ConfigError, match=r"unknown key map\.tsdf\.voxel\b.*known here: .*voxel_size"):
        load_config(overrides=["map.tsdf.voxel=0.1"])
    with pytest.raises(ConfigError, match=r"unknown key nonsense"):
        load_config(overrides=["nonsense=1"])
    with pytest.raises(ConfigError, match=r"unknown key camera\.fps"):
        load_config(overrides=["camera.fps=30"])


def test_wrong_types_are_named() -> None:
    with pytest.raises(ConfigError, match=r"config: map\.resolution: expected number, got 'fine'"):
        load_config(overrides=["map.resolution=fine"])
    with pytest.raises(ConfigError, match=r"config: camera\.width: expected int, got 'wide'"):
        load_config(overrides=["camera.width=wide"])
    with pytest.raises(ConfigError, match=r"config: map\.tsdf: expected a table"):
        load_config(overrides=["map.tsdf=3"])
    with pytest.raises(ConfigError, match=r"config: explore\.max_step_m: expected number, got \[1\]"):
        load_config(overrides=["explore.max_step_m=[1]"])


def test_bool_is_not_an_int_or_a_number() -> None:
    with pytest.raises(ConfigError, match=r"camera\.width: expected int, got True"):
        load_config(overrides=["camera.width=true"])
    with pytest.raises(ConfigError, match=r"map\.resolution: expected number, got False"):
        load_config(overrides=["map.resolution=false"])


def test_validation_from_sim_params_names_the_key() -> None:
    with pytest.raises(ConfigError, match=r"vlm\.sim\.skill"):
        load_config(overrides=["vlm.sim.skill=3"])
    with pytest.raises(ConfigError, match=r"vlm\.sim\.misread"):
        load_config(overrides=["vlm.sim.misread=-0.5"])
    assert load_config(overrides=["vlm.sim.skill=1"]).vlm.sim.skill == 1.0


@pytest.mark.parametrize("item", ["camera.width", "=3", "", "novalue"])
def test_override_without_key_or_equals(item: str) -> None:
    with pytest.raises(ConfigError, match=r"expected key=value"):
        load_config(overrides=[item])


def test_toml_file(tmp_path: Path) -> None:
    path = tmp_path / "homebot.toml"
    path.write_text(
        """
[camera]
width = 640
hfov_deg = 70

[bus]
listen = ["tcp/127.0.0.1:7000"]

[map]
resolution = 0.1

[map.tsdf]
voxel_size = 0.05

[vlm.sim]
skill = 0.5
"""
    )
    config = load_config(path)
    assert config.camera.width == 640 and config.camera.hfov_deg == 70.0
    assert config.bus.listen == ("tcp/127.0.0.1:7000",)
    assert config.map.resolution == 0.1 and config.map.tsdf.voxel_size == 0.05
    assert config.vlm.sim.skill == 0.5
    # overrides come after the file
    assert load_config(path, ["camera.width=1024"]).camera.width == 1024


def test_toml_file_errors_name_the_key(tmp_path: Path) -> None:
    path = tmp_path / "bad-key.toml"
    path.write_text("[explore]\nmax_step = 2.0\n")
    with pytest.raises(ConfigError, match=r"unknown key explore\.max_step\b"):
        load_config(path)
    path.write_text('[camera]\nwidth = "wide"\n')
    with pytest.raises(ConfigError, match=r"camera\.width: expected int"):
        load_config(path)


def test_malformed_toml_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text("[camera\nwidth = = 3\n")
    with pytest.raises(ConfigError, match=r"config file .*broken\.toml"):
        load_config(path)


def test_missing_file_names_the_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"config file .*nowhere\.toml"):
        load_config(tmp_path / "nowhere.toml")


def test_merge_on_a_sub_config() -> None:
    bus = merge(BusSettings(), {"query_timeout_s": 2})
    assert bus.query_timeout_s == 2.0 and bus.listen == BusSettings().listen
    with pytest.raises(ConfigError, match=r"config: top level: expected a table"):
        merge(Config(), [])  # type: ignore[arg-type]
