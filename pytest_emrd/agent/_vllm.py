"""Serving the open models with vLLM: the ``vllm serve`` commands and what a refusal means.

:func:`serve_command` gives the command for a shipped open model (the README shows the same
strings; a test keeps them equal). :func:`vllm_fix` reads a refused request (HTTP status and
body) and names the flag that fixes it, for preflight checks and error messages.

Flag syntax is vLLM >= 0.11.0 (the first release with Qwen3-VL): ``--limit-mm-per-prompt``
takes JSON since 0.10.0 (the older ``image=10`` form is refused, vllm-project/vllm#21615).
Sizes, measured with :func:`~pytest_emrd.agent.build_request` on a full history window of the
``scout`` agent (README "Serving the open models with vLLM" has the arithmetic): at most
:data:`~pytest_emrd.agent.HISTORY_TURNS` frames, and prompt plus ``max_tokens`` 4096 stays
under 30.5k tokens for every model, so 32768 tokens of context fit all four.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Final

from pytest_emrd.agent._config import ModelConfig
from pytest_emrd.agent._history import HISTORY_TURNS

MAX_MODEL_LEN: Final = 32768
"""``--max-model-len`` for the four shipped open models (full window + max_tokens fits)."""
IMAGE_LIMIT_FLAG: Final = f"--limit-mm-per-prompt '{{\"image\": {HISTORY_TURNS}}}'"
CONTEXT_FLAG: Final = f"--max-model-len {MAX_MODEL_LEN}"
KEY_FLAG: Final = "--api-key"

_MODEL_FLAGS: Final[dict[str, tuple[str, ...]]] = {
    "Qwen/Qwen3-VL-32B-Instruct": (),
    "AIDC-AI/Ovis2-34B": ("--trust-remote-code",),
    "mistralai/Pixtral-12B-2409": (
        "--tokenizer-mode mistral",
        "--config-format mistral",
        "--load-format mistral",
    ),
    "OpenGVLab/InternVL3-14B": ("--trust-remote-code",),
}
"""Model-specific flags: ``trust_remote_code`` for Ovis2 and InternVL (vLLM's
``examples/offline_inference/vision_language_multi_image.py``), the ``mistral`` tokenizer,
config and load formats for Pixtral-12B-2409 (Mistral's vLLM deployment guide)."""


def serve_command(config: ModelConfig, *, port: int = 8000) -> str:
    """The ``vllm serve`` command for a shipped open model (``KeyError`` for any other)."""
    flags = (
        *_MODEL_FLAGS[config.model_id],
        IMAGE_LIMIT_FLAG,
        CONTEXT_FLAG,
        f"--port {port}",
    )
    return " \\\n    ".join((f"vllm serve {config.model_id}", *flags))


@dataclass(frozen=True)
class VllmFix:
    """What a vLLM refusal means and the flag that fixes it."""

    problem: str
    """``image_limit``, ``context_length``, ``unauthorized`` or ``unknown_model``."""
    flag: str
    """The flag to add (a ``vllm serve`` flag, or ``api_key_env`` on our side)."""
    hint: str
    """One sentence for the user, naming the flag and the value to give it."""


_IMAGE_LIMIT = re.compile(r"At most (?P<limit>\d+) image\(s\) may be provided in one prompt")
_CONTEXT = re.compile(
    r"maximum context length is (?P<limit>\d+) tokens"
    r"|longer than the maximum model length of (?P<limit2>\d+)"
    r"|too long to fit into the model \(context length (?P<limit3>\d+)\)"
)
_UNKNOWN_MODEL = re.compile(r"The model `(?P<model>[^`]+)` does not exist")


def vllm_fix(status: int, body: str, *, model_id: str = "<model>") -> VllmFix | None:
    """The flag that fixes a vLLM refusal (HTTP ``status``, response ``body``); None if unknown.

    Known refusals (vLLM's own messages): the per-prompt image limit, the context length
    (three wordings across vLLM versions), 401 from a server started with ``--api-key``,
    and 404 for a model the server does not serve.
    """
    if match := _IMAGE_LIMIT.search(body):
        return VllmFix(
            "image_limit",
            "--limit-mm-per-prompt",
            f"the server accepts {match['limit']} image(s) per prompt and the history window "
            f"sends up to {HISTORY_TURNS}: restart vllm serve with {IMAGE_LIMIT_FLAG}.",
        )
    if match := _CONTEXT.search(body):
        limit = match["limit"] or match["limit2"] or match["limit3"]
        return VllmFix(
            "context_length",
            "--max-model-len",
            f"the server's context is {limit} tokens and a full history window plus "
            f"max_tokens needs more: restart vllm serve with {CONTEXT_FLAG}.",
        )
    if status == 401:
        return VllmFix(
            "unauthorized",
            "api_key_env",
            f"the server was started with {KEY_FLAG} (or VLLM_API_KEY): export the same key "
            "in VLLM_API_KEY here (the registry's api_key_env), or restart it without.",
        )
    if match := _UNKNOWN_MODEL.search(body):
        return VllmFix(
            "unknown_model",
            "--served-model-name",
            f"the server does not serve {match['model']!r}: start it with vllm serve "
            f"{model_id}, or add --served-model-name {model_id}.",
        )
    return None
