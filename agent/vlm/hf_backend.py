"""The `hf` VLM backend: a Hugging Face vision-language model loaded from a local folder.

This is the paper's scoring exactly: one forward pass over the chat-formatted prompt and the image
(letters drawn on it), then a softmax over the candidates' logits at the last position. Each
candidate must be one token of the model's vocabulary; a candidate spelt by two tokens ("A" and
" A") counts with both, as the probability mass of the two spellings.

Nothing is downloaded: the folder must hold what ``save_pretrained`` wrote for the model and its
processor, and both are loaded with ``local_files_only=True``. `transformers` is an optional
dependency (``pip install 'homebot[hf]'``), imported only when this backend is built.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from agent.vlm.annotate import draw_marks
from agent.vlm.errors import VLMError
from agent.vlm.protocol import VisualQuery, softmax
from agent.vlm.settings import HFSettings

log = logging.getLogger(__name__)


class HuggingFaceVLM:
    """A `VisionLanguageModel` scored from a local image-text-to-text model's next-token logits.

    Args:
        settings: the model's folder and the device.

    Raises:
        VLMError: transformers is not installed, or the folder, device or model cannot be used.
    """

    name = "hf"

    def __init__(self, settings: HFSettings) -> None:
        self.path = _model_folder(settings.path)
        try:
            import torch
            from transformers import AutoModelForImageTextToText, AutoProcessor
        except ImportError as error:
            raise VLMError(f"the hf VLM backend needs transformers ({error}): pip install 'homebot[hf]'") from None
        self._torch = torch
        self.device = _device(torch, settings.device)
        # Half-precision weights run on the GPU as saved; on the CPU, float32 is the reliable choice.
        dtype = "auto" if self.device.type == "cuda" else torch.float32
        try:
            self.processor = AutoProcessor.from_pretrained(self.path, local_files_only=True)
            model = AutoModelForImageTextToText.from_pretrained(self.path, local_files_only=True, dtype=dtype)
        except (OSError, ValueError, KeyError) as error:
            raise VLMError(f"could not load a vision-language model and its processor from {self.path}: {error}") from None
        self.model = model.to(self.device).train(False)  # inference mode: no dropout
        self.tokenizer = self.processor.tokenizer
        self._token_ids: dict[str, tuple[int, ...]] = {}
        log.info("hf VLM: %s from %s on %s", type(self.model).__name__, self.path, self.device)

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        """P(candidate) from the model's next-token logits, each candidate's tokens pooled (log-sum-exp).

        Args:
            query: the image, the prompt and the candidates.

        Returns:
            The probabilities, summing to 1.
        """
        ids = [self._candidate_token_ids(c) for c in query.candidates]
        _check_distinct(query.candidates, ids)
        logits = self._next_token_logits(query)
        scores = np.array([float(self._torch.logsumexp(logits[list(token_ids)], dim=0)) for token_ids in ids])
        return softmax(query.candidates, scores)

    def _next_token_logits(self, query: VisualQuery) -> Any:
        """The logits over the vocabulary for the token after the assistant's turn begins."""
        image = Image.fromarray(draw_marks(query.observation.rgb, query.marks))
        messages = [{"role": "user", "content": [{"type": "image"}, {"type": "text", "text": query.prompt}]}]
        try:
            text = self.processor.apply_chat_template(messages, add_generation_prompt=True)
        except ValueError as error:
            raise VLMError(f"the processor in {self.path} cannot format a chat ({error}); "
                           "the hf backend needs a model with a chat template") from None
        inputs = self.processor(images=image, text=text, return_tensors="pt").to(self.device, dtype=self.model.dtype)
        with self._torch.inference_mode():
            return self.model(**inputs).logits[0, -1].float()

    def _candidate_token_ids(self, candidate: str) -> tuple[int, ...]:
        """The ids of the single tokens that spell ``candidate`` bare or after a space.

        Decoding each id back to the candidate rejects an unknown word's ``<unk>`` and a tokenizer
        that changes case, either of which would score some other token.
        """
        if candidate not in self._token_ids:
            spellings = {text: self.tokenizer.encode(text, add_special_tokens=False) for text in (candidate, " " + candidate)}
            ids = sorted({ids[0] for ids in spellings.values()
                          if len(ids) == 1 and self.tokenizer.decode(ids).strip() == candidate})
            if not ids:
                tokens = "; ".join(f"{text!r} -> {self.tokenizer.convert_ids_to_tokens(ids)}"
                                   for text, ids in spellings.items())
                raise VLMError(f"candidate {candidate!r} is not a single token of the tokenizer in {self.path} "
                               f"({tokens}); the hf backend scores one next token, so each candidate must be one")
            self._token_ids[candidate] = tuple(ids)
        return self._token_ids[candidate]


def _model_folder(path: str) -> Path:
    """The folder to load from, refused early when it cannot hold a model: no hub name, no download."""
    if not path:
        raise VLMError("the hf VLM backend needs vlm.hf.path: a local folder with a model saved by save_pretrained")
    folder = Path(path).expanduser()
    if not folder.is_dir():
        raise VLMError(f"the hf VLM backend loads from a local folder and downloads nothing; {folder} is not a folder")
    if not (folder / "config.json").is_file():
        raise VLMError(f"{folder} holds no Hugging Face model (no config.json); save one there with "
                       "model.save_pretrained and processor.save_pretrained, or download it beforehand")
    return folder


def _device(torch: Any, name: str) -> Any:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(name)
    except RuntimeError as error:
        raise VLMError(f"vlm.hf.device: {error}") from None
    if device.type == "cuda" and not torch.cuda.is_available():
        raise VLMError(f"vlm.hf.device is {name!r} but torch sees no CUDA device; use 'auto' or 'cpu'")
    return device


def _check_distinct(candidates: tuple[str, ...], ids: list[tuple[int, ...]]) -> None:
    """Two candidates scored by one token would split one probability between them: refuse."""
    owner: dict[int, str] = {}
    for candidate, token_ids in zip(candidates, ids):
        for token_id in token_ids:
            if token_id in owner:
                raise VLMError(f"candidates {owner[token_id]!r} and {candidate!r} are the same token; "
                               "the hf backend cannot tell them apart")
            owner[token_id] = candidate
