"""The `openai` VLM backend against a real HTTP server on loopback that speaks chat completions."""

from __future__ import annotations

import base64
import io
import json
import math
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import numpy as np
import pytest
from PIL import Image

from agent.mapping.camera import Intrinsics
from agent.observation import Observation
from agent.vlm.errors import VLMError
from agent.vlm.openai_backend import OpenAIVLM
from agent.vlm.protocol import VisualQuery
from agent.vlm.settings import OpenAISettings

H, W = 48, 64
MARKS = {"A": (12.0, 20.0), "B": (50.0, 30.0)}
LETTERS = ("A", "B", "C", "D")


@dataclass
class FakeServer:
    """What the server replies (a queue of (status, body); the last one repeats) and what it got."""

    url: str
    replies: list[tuple[int, Any]] = field(default_factory=list)
    requests: list[tuple[dict[str, str], Any]] = field(default_factory=list)

    def next_reply(self) -> tuple[int, Any]:
        return self.replies.pop(0) if len(self.replies) > 1 else self.replies[0]


def completion(top: dict[str, float]) -> dict[str, Any]:
    """A chat-completions reply whose first token has these (token -> probability) alternatives."""
    entries = [{"token": token, "logprob": math.log(p), "bytes": list(token.encode())} for token, p in top.items()]
    first = entries[0]
    return {
        "id": "cmpl-1",
        "object": "chat.completion",
        "choices": [{
            "index": 0,
            "message": {"role": "assistant", "content": first["token"]},
            "logprobs": {"content": [{**first, "top_logprobs": entries}]},
            "finish_reason": "length",
        }],
    }


@pytest.fixture
def server() -> Iterator[FakeServer]:
    fake = FakeServer(url="")

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:  # noqa: N802 (the http.server API)
            body = self.rfile.read(int(self.headers["Content-Length"]))
            fake.requests.append((dict(self.headers), json.loads(body)))
            if self.path != "/v1/chat/completions":
                status, reply = 404, {"error": {"message": f"no route {self.path}"}}
            else:
                status, reply = fake.next_reply()
            data = reply if isinstance(reply, bytes) else json.dumps(reply).encode()
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args: Any) -> None:
            """Quiet: pytest shows failures, not every request."""

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    fake.url = f"http://127.0.0.1:{httpd.server_address[1]}/v1"
    thread = threading.Thread(target=httpd.serve_forever, args=(0.01,), daemon=True)
    thread.start()
    try:
        yield fake
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(5.0)


@pytest.fixture(autouse=True)
def no_proxy_or_key(monkeypatch: pytest.MonkeyPatch) -> None:
    """Loopback requests must not go through a proxy, and no real key may leak into a test."""
    for name in ("HTTP_PROXY", "http_proxy", "HTTPS_PROXY", "https_proxy", "ALL_PROXY", "all_proxy",
                 "OPENAI_API_KEY", "HOMEBOT_VLM_API_KEY", "HOMEBOT_VLM_BASE_URL", "HOMEBOT_VLM_MODEL"):
        monkeypatch.delenv(name, raising=False)


def backend(server: FakeServer, **changes: Any) -> OpenAIVLM:
    settings = dict(base_url=server.url, model="llava-test", timeout_s=5.0, retries=2, backoff_s=0.001, top_logprobs=5)
    return OpenAIVLM(OpenAISettings(**{**settings, **changes}))


def query(candidates: tuple[str, ...] = LETTERS, marks: dict[str, tuple[float, float]] | None = None) -> VisualQuery:
    rgb = np.zeros((H, W, 3), dtype=np.uint8)
    rgb[:, :, 1] = np.arange(W, dtype=np.uint8)[None, :] * 3  # a gradient, so the frame is not blank
    observation = Observation(rgb, np.ones((H, W), np.float32), np.full((H, W), -1, np.int32), (),
                              Intrinsics(W, H, 32.0, 32.0, 32.0, 24.0), np.eye(4), (0.0, 0.0, 0.0))
    return VisualQuery(observation, "Which direction would you explore? Answer with a single letter.",
                       candidates, MARKS if marks is None else marks)


def sent_image(body: dict[str, Any]) -> np.ndarray:
    content = body["messages"][0]["content"]
    url = next(part["image_url"]["url"] for part in content if part["type"] == "image_url")
    prefix = "data:image/png;base64,"
    assert url.startswith(prefix)
    png = base64.b64decode(url[len(prefix):])
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def test_request_carries_the_protocol_and_the_marked_image(server: FakeServer) -> None:
    server.replies = [(200, completion({" A": 0.6, " B": 0.3, "C": 0.05, "D": 0.05}))]
    q = query()
    backend(server).probabilities(q)
    (headers, body), = server.requests
    assert body["model"] == "llava-test"
    assert body["max_tokens"] == 1 and body["temperature"] == 0
    assert body["logprobs"] is True and body["top_logprobs"] == 5
    message, = body["messages"]
    assert message["role"] == "user"
    assert [part["type"] for part in message["content"]] == ["image_url", "text"]
    assert message["content"][1]["text"] == q.prompt
    assert "Authorization" not in headers
    image = sent_image(body)
    raw = q.observation.rgb
    assert image.shape == raw.shape
    for u, v in MARKS.values():  # the disc's white shows around each mark ...
        patch = (slice(int(v) - 4, int(v) + 5), slice(int(u) - 4, int(u) + 5))
        assert np.abs(image[patch].astype(int) - raw[patch]).sum() > 0
        assert (image[patch] == 255).all(axis=-1).any()
    assert np.array_equal(image[:, 30:40], raw[:, 30:40])  # ... and the rest of the frame is untouched


def test_probabilities_are_normalised_over_the_candidates(server: FakeServer) -> None:
    server.replies = [(200, completion({"A": 0.5, "B": 0.2, "C": 0.1, "D": 0.1, "The": 0.05}))]
    probs = backend(server).probabilities(query())
    assert list(probs) == list(LETTERS)
    assert sum(probs.values()) == pytest.approx(1.0)
    assert probs == pytest.approx({"A": 0.5 / 0.9, "B": 0.2 / 0.9, "C": 0.1 / 0.9, "D": 0.1 / 0.9})


def test_leading_space_and_case_spellings_add_up(server: FakeServer) -> None:
    server.replies = [(200, completion({" Yes": 0.4, "Yes": 0.2, " yes": 0.1, "No": 0.2, " Maybe": 0.1}))]
    probs = backend(server).probabilities(query(("Yes", "No"), marks={}))
    assert probs["Yes"] == pytest.approx(0.7 / 0.9)
    assert probs["No"] == pytest.approx(0.2 / 0.9)


def test_a_candidate_missing_from_top_logprobs_gets_half_the_smallest(server: FakeServer) -> None:
    server.replies = [(200, completion({" A": 0.7, " B": 0.2, "Hello": 0.04}))]
    probs = backend(server).probabilities(query())
    floor = 0.5 * 0.04
    total = 0.7 + 0.2 + 2 * floor
    assert probs == pytest.approx({"A": 0.7 / total, "B": 0.2 / total, "C": floor / total, "D": floor / total})


def test_no_candidate_in_top_logprobs_answers_uniformly(server: FakeServer) -> None:
    server.replies = [(200, completion({"I": 0.6, "The": 0.3}))]
    assert backend(server).probabilities(query(("Yes", "No"), marks={})) == pytest.approx({"Yes": 0.5, "No": 0.5})


def test_a_reply_without_logprobs_is_a_clear_error(server: FakeServer) -> None:
    reply = completion({"A": 1.0})
    reply["choices"][0]["logprobs"] = None
    server.replies = [(200, reply)]
    with pytest.raises(VLMError, match="returned no logprobs") as error:
        backend(server).probabilities(query())
    assert server.url in str(error.value) and "--max-logprobs" in str(error.value)


def test_a_reply_that_is_not_json_is_a_clear_error(server: FakeServer) -> None:
    server.replies = [(200, b"<html>proxy says hi</html>")]
    with pytest.raises(VLMError, match="not JSON.*proxy says hi"):
        backend(server).probabilities(query())


def test_transient_failures_are_retried(server: FakeServer) -> None:
    server.replies = [(503, {"error": "loading"}), (503, {"error": "loading"}), (200, completion({"A": 0.9, "B": 0.1}))]
    probs = backend(server).probabilities(query(("A", "B")))
    assert probs["A"] == pytest.approx(0.9)
    assert len(server.requests) == 3


def test_retries_are_bounded(server: FakeServer) -> None:
    server.replies = [(503, {"error": "overloaded"})]
    with pytest.raises(VLMError, match=r"HTTP 503.*overloaded.*after 3 tries"):
        backend(server).probabilities(query())
    assert len(server.requests) == 3


def test_a_refused_request_is_not_retried(server: FakeServer) -> None:
    server.replies = [(401, {"error": {"message": "invalid api key"}})]
    with pytest.raises(VLMError, match=r"HTTP 401.*invalid api key.*HOMEBOT_VLM_API_KEY"):
        backend(server).probabilities(query())
    assert len(server.requests) == 1


def test_a_wrong_base_url_says_so(server: FakeServer) -> None:
    server.replies = [(200, completion({"A": 1.0}))]
    with pytest.raises(VLMError, match=r"HTTP 404.*/v1"):
        backend(server, base_url=server.url.removesuffix("/v1")).probabilities(query())


def test_an_unreachable_server_is_an_error_after_the_retries() -> None:
    import socket

    with socket.socket() as probe:  # a port that nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    vlm = OpenAIVLM(OpenAISettings(base_url=f"http://127.0.0.1:{port}/v1", model="m", retries=1, backoff_s=0.001))
    with pytest.raises(VLMError, match=rf"127.0.0.1:{port}.*could not be reached.*after 2 tries"):
        vlm.probabilities(query())


def test_the_api_key_is_sent_as_a_bearer_token(server: FakeServer, monkeypatch: pytest.MonkeyPatch) -> None:
    server.replies = [(200, completion({"A": 1.0}))]
    monkeypatch.setenv("OPENAI_API_KEY", "sk-fallback")
    backend(server).probabilities(query())
    monkeypatch.setenv("HOMEBOT_VLM_API_KEY", "sk-homebot")
    backend(server).probabilities(query())
    monkeypatch.setenv("MY_KEY", "sk-mine")
    backend(server, api_key_env="MY_KEY").probabilities(query())
    assert [headers["Authorization"] for headers, _ in server.requests] == [
        "Bearer sk-fallback", "Bearer sk-homebot", "Bearer sk-mine"]


def test_base_url_and_model_come_from_the_environment(server: FakeServer, monkeypatch: pytest.MonkeyPatch) -> None:
    server.replies = [(200, completion({"A": 1.0}))]
    monkeypatch.setenv("HOMEBOT_VLM_BASE_URL", server.url + "/")
    monkeypatch.setenv("HOMEBOT_VLM_MODEL", "from-env")
    OpenAIVLM(OpenAISettings(backoff_s=0.001)).probabilities(query())
    assert server.requests[0][1]["model"] == "from-env"


def test_a_model_name_is_required() -> None:
    with pytest.raises(VLMError, match="HOMEBOT_VLM_MODEL"):
        OpenAIVLM(OpenAISettings(base_url="http://127.0.0.1:9/v1"))
