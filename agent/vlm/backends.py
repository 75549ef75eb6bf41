"""Building the VLM the configuration asks for: `sim`, `openai` or `hf`.

`transformers` stays an optional dependency: the `hf` backend imports it only when it is built.
"""

from __future__ import annotations

from collections.abc import Callable

from agent.vlm.errors import VLMError
from agent.vlm.hf_backend import HuggingFaceVLM
from agent.vlm.openai_backend import OpenAIVLM
from agent.vlm.protocol import VisionLanguageModel
from agent.vlm.settings import VLMSettings
from agent.vlm.sim import SimulatedVLM

FACTORIES: dict[str, Callable[[VLMSettings], VisionLanguageModel]] = {
    "sim": lambda settings: SimulatedVLM(settings.sim),
    "openai": lambda settings: OpenAIVLM(settings.openai),
    "hf": lambda settings: HuggingFaceVLM(settings.hf),
}


def make_vlm(settings: VLMSettings) -> VisionLanguageModel:
    """The backend named by ``settings.backend``; a `VLMError` names the known ones otherwise.

    Args:
        settings: the VLM's settings.

    Returns:
        The backend.

    Raises:
        VLMError: an unknown backend.
    """
    factory = FACTORIES.get(settings.backend)
    if factory is None:
        raise VLMError(f"unknown VLM backend {settings.backend!r} (known: {', '.join(FACTORIES)})")
    return factory(settings)
