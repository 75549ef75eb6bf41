"""Choosing a VLM backend by name, and the `[vlm]` settings that choose it."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from agent.app.config import ConfigError, merge
from agent.vlm.backends import FACTORIES, make_vlm
from agent.vlm.errors import VLMError
from agent.vlm.openai_backend import OpenAIVLM
from agent.vlm.settings import BACKENDS, OpenAISettings, VLMSettings
from agent.vlm.sim import SimParams, SimulatedVLM


def test_every_known_backend_has_a_factory() -> None:
    assert set(FACTORIES) == set(BACKENDS)


def test_sim_is_the_default_and_takes_its_params() -> None:
    vlm = make_vlm(VLMSettings(sim=SimParams(seed=7)))
    assert isinstance(vlm, SimulatedVLM) and vlm.params.seed == 7


def test_openai_is_built_from_its_settings() -> None:
    vlm = make_vlm(VLMSettings(backend="openai", openai=OpenAISettings(base_url="http://gpu:8000/v1/", model="m")))
    assert isinstance(vlm, OpenAIVLM)
    assert vlm.name == "openai" and vlm.url == "http://gpu:8000/v1/chat/completions"


def test_hf_needs_a_model_folder() -> None:
    with pytest.raises(VLMError, match="vlm.hf.path"):
        make_vlm(VLMSettings(backend="hf"))


def test_an_unknown_backend_lists_the_known_ones() -> None:
    with pytest.raises(ValueError, match="unknown backend 'gpt4'.*sim, openai, hf"):
        VLMSettings(backend="gpt4")
    with pytest.raises(VLMError, match="unknown VLM backend 'gpt4'.*sim, openai, hf"):
        make_vlm(SimpleNamespace(backend="gpt4"))  # type: ignore[arg-type]


def test_settings_merge_from_a_config_table() -> None:
    settings = merge(VLMSettings(), {"backend": "openai", "openai": {"model": "llava", "timeout_s": 5, "top_logprobs": 10},
                                     "hf": {"path": "/models/llava"}, "sim": {"skill": 0.5}})
    assert settings.backend == "openai" and settings.sim.skill == 0.5
    assert settings.openai == OpenAISettings(model="llava", timeout_s=5.0, top_logprobs=10)
    assert settings.hf.path == "/models/llava"
    with pytest.raises(ConfigError, match="vlm.openai.top_logprobs"):
        merge(VLMSettings(), {"openai": {"top_logprobs": 0}})
    with pytest.raises(ConfigError, match="unknown backend"):
        merge(VLMSettings(), {"backend": "nope"})
