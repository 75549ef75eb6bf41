"""The frontier-property UNet: its config, input encoding, shapes and model files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from agent.lfe.model import (
    FILE_FORMAT,
    FrontierUNet,
    ModelFileError,
    UNetConfig,
    encode_input,
    from_network,
    load_model,
    map_window,
    save_model,
    to_network,
)
from agent.lfe.raster import FREE, OCCUPIED, UNKNOWN

SMALL = UNetConfig(base_channels=4, depth=3)


class Payload:
    """Something a pickle-based loader would construct (and so could run code for)."""


@pytest.mark.parametrize(("values", "field"), [
    ({"base_channels": 0}, "base_channels"),
    ({"depth": 0}, "depth"),
    ({"depth": 2.5}, "depth"),
    ({"in_channels": 3}, "in_channels"),
    ({"out_channels": 1}, "out_channels"),
    ({"model_resolution": 0.0}, "model_resolution"),
    ({"model_resolution": float("nan")}, "model_resolution"),
])
def test_config_errors_name_the_field(values: dict, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{field}:"):
        UNetConfig(**values)


def test_config_round_trips_through_a_plain_dict_and_refuses_unknown_keys() -> None:
    assert UNetConfig.from_dict(SMALL.to_dict()) == SMALL
    with pytest.raises(ValueError, match="unknown UNetConfig fields: width"):
        UNetConfig.from_dict({**SMALL.to_dict(), "width": 3})


def test_encode_input_is_one_hot_map_plus_frontier_mask() -> None:
    maps = np.array([[[UNKNOWN, OCCUPIED, FREE], [FREE, FREE, UNKNOWN]]], dtype=np.uint8)
    mask = np.array([[[False, False, True], [True, False, False]]])
    x = encode_input(maps, mask)
    assert x.shape == (1, 4, 2, 3) and x.dtype == torch.float32
    torch.testing.assert_close(x[0, :3].argmax(dim=0), torch.as_tensor(maps[0]).long())
    torch.testing.assert_close(x[0, :3].sum(dim=0), torch.ones(2, 3))
    torch.testing.assert_close(x[0, 3], torch.as_tensor(mask[0]).float())
    with pytest.raises(ValueError, match="encode_map values"):
        encode_input(maps + 1, mask)
    with pytest.raises(ValueError, match=r"\(B, H, W\)"):
        encode_input(maps[0], mask[0])


def test_targets_round_trip_through_network_units_and_clip_at_zero() -> None:
    natural = torch.tensor([[0.0, 2.0, 200.0]])
    torch.testing.assert_close(from_network(to_network(natural)), natural)
    assert from_network(torch.tensor([-3.0])).item() == 0.0


@pytest.mark.parametrize("size", [(37, 53), (5, 3), (64, 64)])
def test_forward_keeps_any_size(size: tuple[int, int]) -> None:
    model = FrontierUNet(SMALL).eval()
    with torch.inference_mode():
        out = model(torch.zeros(2, 4, *size))
    assert out.shape == (2, 3, *size)


def test_default_model_is_small_enough_to_ship(tmp_path: Path) -> None:
    config = UNetConfig()
    save_model(tmp_path / "m.pt", FrontierUNet(config), config, {})
    assert 1e6 < (tmp_path / "m.pt").stat().st_size < 3e6


def test_map_window_pads_with_unknown_beyond_the_edges() -> None:
    encoded = np.full((4, 5), FREE, dtype=np.uint8)
    window = map_window(encoded, np.array([-1, 3]), (3, 4))
    expected = np.array([[0, 0, 0, 0], [2, 2, 0, 0], [2, 2, 0, 0]], dtype=np.uint8)
    np.testing.assert_array_equal(window, expected)
    assert not map_window(encoded, np.array([10, 10]), (2, 2)).any()


def trained_a_little(config: UNetConfig) -> FrontierUNet:
    """A model whose batch-norm statistics have moved off their initial values."""
    torch.manual_seed(3)
    model = FrontierUNet(config).train()
    model(torch.rand(2, 4, 16, 16))
    return model.eval()


def test_save_and_load_give_identical_outputs_and_metadata(tmp_path: Path) -> None:
    model = trained_a_little(SMALL)
    metadata = {"epoch": 4, "val_mae": {"area_m2": 1.5}, "homes": ["home-00001"]}
    save_model(tmp_path / "m.pt", model, SMALL, metadata)
    loaded, config, read = load_model(tmp_path / "m.pt")
    assert config == SMALL and read == metadata and not loaded.training
    x = encode_input(np.random.default_rng(0).integers(0, 3, (1, 21, 30)), np.zeros((1, 21, 30), bool))
    with torch.inference_mode():
        torch.testing.assert_close(loaded(x), model(x), rtol=0, atol=0)


def test_metadata_must_be_plain_data(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="JSON-able"):
        save_model(tmp_path / "m.pt", FrontierUNet(SMALL), SMALL, {"when": object()})
    assert not (tmp_path / "m.pt").exists()


def test_missing_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="nowhere.pt"):
        load_model(tmp_path / "nowhere.pt")


def test_corrupt_and_truncated_files_are_refused_naming_the_path(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"not a model at all")
    with pytest.raises(ModelFileError, match="garbage.pt: corrupt"):
        load_model(garbage)
    save_model(tmp_path / "whole.pt", FrontierUNet(SMALL), SMALL, {})
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes((tmp_path / "whole.pt").read_bytes()[:2000])
    with pytest.raises(ModelFileError, match="truncated.pt"):
        load_model(truncated)


def test_a_file_that_would_construct_objects_is_refused_not_run(tmp_path: Path) -> None:
    path = tmp_path / "code.pt"
    torch.save({"format": FILE_FORMAT, "payload": Payload()}, path)
    with pytest.raises(ModelFileError, match="code.pt"):
        load_model(path)


def test_foreign_and_mismatched_files_are_refused(tmp_path: Path) -> None:
    foreign = tmp_path / "foreign.pt"
    torch.save({"weights": torch.zeros(3)}, foreign)
    with pytest.raises(ModelFileError, match="foreign.pt: not a homebot-lfe-unet/1"):
        load_model(foreign)
    mismatched = tmp_path / "mismatched.pt"
    save_model(mismatched, FrontierUNet(SMALL), SMALL, {})
    contents = torch.load(mismatched, weights_only=True)
    contents["config"]["depth"] = 2
    torch.save(contents, mismatched)
    with pytest.raises(ModelFileError, match="mismatched.pt: incompatible"):
        load_model(mismatched)
