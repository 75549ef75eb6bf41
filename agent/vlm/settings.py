"""The `[vlm]` settings: which backend answers the VLM queries, and each backend's own knobs.

Every field has a default so a config file names only what it changes. Strings that may be empty
(``base_url``, ``model``, ``path``) fall back to environment variables or fail with a clear message
when the backend is built, so a config file stays valid whichever backend it selects.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from agent.vlm.sim_params import SimParams

BACKENDS = ("sim", "openai", "hf")


@dataclass(frozen=True)
class OpenAISettings:
    """An OpenAI-compatible chat-completions server (vLLM, llama.cpp server, Ollama).

    ``base_url`` and ``model`` fall back to ``HOMEBOT_VLM_BASE_URL`` / ``HOMEBOT_VLM_MODEL`` when
    empty. The API key is never stored in a config file: it is read from the environment variable
    named by ``api_key_env``, then ``OPENAI_API_KEY``; local servers need none.
    """

    base_url: str = ""
    model: str = ""
    api_key_env: str = "HOMEBOT_VLM_API_KEY"
    timeout_s: float = 10.0
    retries: int = 2  # extra tries after the first, on connection errors, timeouts, 429 and 5xx
    backoff_s: float = 0.5  # wait before the first retry; doubles each time
    top_logprobs: int = 20  # OpenAI and vLLM's default --max-logprobs allow at most 20

    def __post_init__(self) -> None:
        if self.timeout_s <= 0:
            raise ValueError(f"vlm.openai.timeout_s: {self.timeout_s} must be positive")
        if self.retries < 0 or self.backoff_s < 0:
            raise ValueError("vlm.openai.retries and vlm.openai.backoff_s must not be negative")
        if self.top_logprobs < 1:
            raise ValueError(f"vlm.openai.top_logprobs: {self.top_logprobs} must be at least 1")


@dataclass(frozen=True)
class HFSettings:
    """A Hugging Face vision-language model in a local folder (nothing is downloaded).

    ``device`` is "auto" (CUDA when available, else CPU) or any torch device string.
    """

    path: str = ""
    device: str = "auto"


@dataclass(frozen=True)
class VLMSettings:
    """Which backend to use (one of `BACKENDS`) and the settings of each."""

    backend: str = "sim"
    sim: SimParams = field(default_factory=SimParams)
    openai: OpenAISettings = field(default_factory=OpenAISettings)
    hf: HFSettings = field(default_factory=HFSettings)

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise ValueError(f"vlm.backend: unknown backend {self.backend!r} (known: {', '.join(BACKENDS)})")
