"""A vLLM-like OpenAI endpoint on 127.0.0.1 that refuses the way vLLM does.

It lists its model with ``max_model_len`` (vLLM's ``ModelCard``), counts the images of a
request against its image limit and the prompt against its context, and answers a refused
request with HTTP 400 and vLLM's own error body (``{"error": {"message", "type":
"BadRequestError", "param", "code": 400}}``) carrying vLLM's sentences (see
``pytest_emrd/preflight/_server.py`` for where each comes from). Accepted requests get a
reply in the EMRD protocol.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import pytest

from pytest_emrd.preflight import count_images, request_tokens, sample_reply

#: vLLM's context refusals across versions: current renderer, older serving layer, engine.
CONTEXT_MESSAGES = {
    "renderer": (
        "You passed {prompt} input tokens and requested {completion} output tokens. However, "
        "the model's context length is only {context} tokens, resulting in a maximum input "
        "length of {room} tokens. Please reduce the length of the input prompt."
    ),
    "serving": (
        "This model's maximum context length is {context} tokens. However, you requested "
        "{completion} output tokens and your prompt contains at least {prompt} input tokens, "
        "for a total of at least {total} tokens. Please reduce the length of the input prompt "
        "or the number of requested output tokens."
    ),
    "engine": (
        "The decoder prompt (length {prompt}) is longer than the maximum model length of "
        "{context}. Make sure that `max_model_len` is no smaller than the number of text "
        "tokens plus multimodal tokens. For image inputs, the number of image tokens depends "
        "on the number of images, and possibly their aspect ratios as well."
    ),
}
IMAGE_TOKENS = 256


@dataclass
class FakeVLLM:
    """Settings of the fake server and what it saw."""

    model_id: str = "Qwen/Qwen3-VL-32B-Instruct"
    image_limit: int = 10
    max_model_len: int = 40960
    context_message: str = "serving"
    requests: list[dict[str, Any]] = field(default_factory=list)
    base_url: str = ""

    def answer(self, method: str, path: str, body: Any) -> tuple[int, dict[str, Any]]:
        """vLLM's answer to ``GET /v1/models`` and ``POST /v1/chat/completions``."""
        if method == "GET":
            card = {
                "id": self.model_id,
                "object": "model",
                "created": 0,
                "owned_by": "vllm",
                "root": self.model_id,
                "parent": None,
                "max_model_len": self.max_model_len,
                "permission": [],
            }
            return 200, {"object": "list", "data": [card]}
        self.requests.append(body)
        if body.get("model") != self.model_id:
            error = {"message": f"The model `{body.get('model')}` does not exist."}
            return 404, {"error": {**error, "type": "NotFoundError", "code": 404}}
        said = self.refusal(body)
        if said is not None:
            error = {"message": said, "type": "BadRequestError", "param": None, "code": 400}
            return 400, {"error": error}
        text = sample_reply()
        usage = {
            "prompt_tokens": request_tokens(body["messages"], image_tokens=IMAGE_TOKENS),
            "completion_tokens": len(text) // 4,
        }
        choice = {"index": 0, "message": {"role": "assistant", "content": text}}
        return 200, {"object": "chat.completion", "choices": [choice], "usage": usage}

    def refusal(self, body: dict[str, Any]) -> str | None:
        messages = body["messages"]
        images = count_images(messages)
        if images > self.image_limit:
            return f"At most {self.image_limit} image(s) may be provided in one prompt."
        prompt = request_tokens(messages, image_tokens=IMAGE_TOKENS)
        completion = int(body.get("max_tokens") or 0)
        if prompt + completion > self.max_model_len:
            return CONTEXT_MESSAGES[self.context_message].format(
                prompt=prompt,
                completion=completion,
                context=self.max_model_len,
                room=self.max_model_len - completion,
                total=prompt + completion,
            )
        return None


@pytest.fixture
def fake_vllm(json_server) -> FakeVLLM:
    """A running fake vLLM server (settings changeable while it runs)."""
    fake = FakeVLLM()
    fake.base_url = json_server(fake.answer)
    return fake


@pytest.fixture
def registry_for(tmp_path):
    """A user registry pointing ``qwen3-vl-32b`` at ``base_url``: the path of the file."""

    def write(base_url: str, **fields: Any) -> Any:
        entry = {"base_url": base_url, **fields}
        path = tmp_path / "models.yaml"
        path.write_text(json.dumps({"models": {"qwen3-vl-32b": entry}}), encoding="utf-8")
        return path

    return write


@pytest.fixture
def unused_port() -> int:
    """A port nothing listens on (bound, then released)."""
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])
