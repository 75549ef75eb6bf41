"""The `openai` VLM backend: any OpenAI-compatible chat-completions server (vLLM, llama.cpp server,
Ollama) that returns log-probabilities.

One request per query: the frame (letters drawn on it) and the prompt in one user message, asking for
a single token with its ``top_logprobs``. The candidates' probabilities are read from those
alternatives, which is as close to "the next-token scores" of the paper as a remote API gets.

A candidate absent from the top K gets a floor of half the smallest returned probability: every
token outside the top K is at most that likely, and halving keeps it below every token that was
returned. HTTP goes through the standard library; nothing in a reply is evaluated.
"""

from __future__ import annotations

import base64
import http.client
import io
import json
import logging
import math
import os
import time
import urllib.error
import urllib.request
from typing import Any

import numpy as np
from PIL import Image

from agent.vlm.annotate import draw_marks
from agent.vlm.errors import VLMError
from agent.vlm.protocol import VisualQuery
from agent.vlm.settings import OpenAISettings

log = logging.getLogger(__name__)

DEFAULT_BASE_URL = "http://127.0.0.1:8000/v1"
_RETRY_STATUS = frozenset({408, 429}) | frozenset(range(500, 600))
_BODY_EXCERPT = 300


class OpenAIVLM:
    """A `VisionLanguageModel` served over the OpenAI chat-completions API.

    Args:
        settings: the server, the model and the API key's variable.

    Raises:
        VLMError: no model name is set.
    """

    name = "openai"

    def __init__(self, settings: OpenAISettings = OpenAISettings()) -> None:
        self.settings = settings
        base_url = settings.base_url or os.environ.get("HOMEBOT_VLM_BASE_URL") or DEFAULT_BASE_URL
        self.url = base_url.rstrip("/") + "/chat/completions"
        self.model = settings.model or os.environ.get("HOMEBOT_VLM_MODEL", "")
        if not self.model:
            raise VLMError(f"the openai VLM backend needs a model name, as the server at {base_url} serves it: "
                           "set vlm.openai.model or HOMEBOT_VLM_MODEL")
        self._api_key = os.environ.get(settings.api_key_env) or os.environ.get("OPENAI_API_KEY")

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        """P(candidate) from the top log-probabilities of the server's first answer token.

        Args:
            query: the image, the prompt and the candidates.

        Returns:
            The probabilities, summing to 1.
        """
        reply = self._post(self._request_body(query))
        return candidate_probabilities(self._top_logprobs(reply), query.candidates)

    def _request_body(self, query: VisualQuery) -> dict[str, Any]:
        image_url = png_data_url(draw_marks(query.observation.rgb, query.marks))
        content = [
            {"type": "image_url", "image_url": {"url": image_url}},
            {"type": "text", "text": query.prompt},
        ]
        return {
            "model": self.model,
            "messages": [{"role": "user", "content": content}],
            "max_tokens": 1,
            "temperature": 0,
            "logprobs": True,
            "top_logprobs": self.settings.top_logprobs,
        }

    def _post(self, body: dict[str, Any]) -> Any:
        """The parsed JSON reply, retrying transient failures with exponential backoff."""
        data = json.dumps(body).encode()
        headers = {"Content-Type": "application/json", "Accept": "application/json"}
        if self._api_key:
            headers["Authorization"] = f"Bearer {self._api_key}"
        tries = self.settings.retries + 1
        for attempt in range(tries):
            request = urllib.request.Request(self.url, data=data, headers=headers, method="POST")
            try:
                with urllib.request.urlopen(request, timeout=self.settings.timeout_s) as response:
                    raw = response.read()
                break
            except urllib.error.HTTPError as error:
                detail = error.read()[:_BODY_EXCERPT].decode(errors="replace")
                if error.code not in _RETRY_STATUS:
                    raise VLMError(self._client_error(error.code, detail)) from None
                problem = f"answered HTTP {error.code}: {detail}"
            except (urllib.error.URLError, http.client.HTTPException, TimeoutError, ConnectionError) as error:
                problem = f"could not be reached: {getattr(error, 'reason', error)}"
            if attempt + 1 < tries:
                wait = self.settings.backoff_s * 2**attempt
                log.warning("the VLM server at %s %s; retrying in %.2f s", self.url, problem, wait)
                time.sleep(wait)
        else:
            raise VLMError(f"the VLM server at {self.url} {problem} (gave up after {tries} tries)")
        try:
            return json.loads(raw)
        except (json.JSONDecodeError, UnicodeDecodeError):
            excerpt = raw[:_BODY_EXCERPT].decode(errors="replace")
            raise VLMError(f"the VLM server at {self.url} replied with something that is not JSON: {excerpt!r}") from None

    def _client_error(self, status: int, detail: str) -> str:
        hint = {
            401: f"check the API key in ${self.settings.api_key_env} or $OPENAI_API_KEY",
            403: f"check the API key in ${self.settings.api_key_env} or $OPENAI_API_KEY",
            404: "the base URL usually ends in /v1 (e.g. http://127.0.0.1:8000/v1), and the model must be one it serves",
        }.get(status, f"is {self.model!r} a vision model that this server serves?")
        return f"the VLM server at {self.url} refused the request with HTTP {status}: {detail} ({hint})"

    def _top_logprobs(self, reply: Any) -> list[tuple[str, float]]:
        """(token, logprob) pairs of the first generated token, or a `VLMError` saying what is missing."""
        if isinstance(reply, dict) and reply.get("error"):
            raise VLMError(f"the VLM server at {self.url} reported an error: {str(reply['error'])[:_BODY_EXCERPT]}")
        try:
            entries = reply["choices"][0]["logprobs"]["content"][0]["top_logprobs"]
            pairs = [(str(entry["token"]), float(entry["logprob"])) for entry in entries]
        except (KeyError, IndexError, TypeError, ValueError):
            pairs = []
        if not pairs:
            raise VLMError(
                f"the server at {self.url} returned no logprobs for model {self.model!r}. The openai backend "
                "needs top_logprobs of the first token: vLLM gives up to --max-logprobs (default 20), "
                "llama.cpp's llama-server gives them, Ollama from 0.12.11 on; otherwise the server or "
                "the model does not support logprobs and cannot be used with this backend"
            )
        return pairs


def candidate_probabilities(top_logprobs: list[tuple[str, float]], candidates: tuple[str, ...]) -> dict[str, float]:
    """P(candidate) from one token's alternatives, normalised over ``candidates``.

    A token counts for a candidate when, stripped of surrounding spaces (" A" is how many tokenizers
    spell "A" after a colon), it equals the candidate, or failing that equals it ignoring case.
    Tokens for the same candidate add up. Missing candidates get half the smallest returned
    probability.

    Args:
        top_logprobs: the token's alternatives and their log-probabilities.
        candidates: the answers asked for.

    Returns:
        The probabilities, summing to 1.
    """
    exact = {c: c for c in candidates}
    folded = {c.lower(): c for c in candidates}
    mass = dict.fromkeys(candidates, 0.0)
    for token, logprob in top_logprobs:
        word = token.strip()
        candidate = exact.get(word) or folded.get(word.lower())
        if candidate is not None:
            mass[candidate] += math.exp(logprob)
    floor = 0.5 * min(math.exp(logprob) for _, logprob in top_logprobs)
    if not any(mass.values()):
        log.warning("none of %s is among the server's top %d tokens %s; answering uniformly",
                    candidates, len(top_logprobs), [token for token, _ in top_logprobs])
    values = np.array([mass[c] or floor for c in candidates])
    if values.sum() <= 0.0:  # every returned logprob was -inf
        values = np.ones(len(candidates))
    values /= values.sum()
    return {c: float(p) for c, p in zip(candidates, values)}


def png_data_url(rgb: np.ndarray) -> str:
    """The image as a ``data:image/png;base64,...`` URL: lossless, so the drawn letters stay crisp.

    Args:
        rgb: the image (HxWx3, uint8).

    Returns:
        The URL.
    """
    buffer = io.BytesIO()
    Image.fromarray(rgb).save(buffer, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")
