"""Serving the open models with vLLM: the ``vllm serve`` command of each shipped open model.

:func:`serve_command` gives the command (``docs/user-guide/vllm.md`` shows the same strings; a
test keeps them equal). Reading a server's refusal back into the missing flag is preflight's job
(:func:`pytest_emrd.preflight.vllm_refusal`, run by ``emrd check``).

Flag syntax is vLLM >= 0.11.0 (the first release with Qwen3-VL): ``--limit-mm-per-prompt``
takes JSON since 0.10.0 (the older ``image=10`` form is refused, vllm-project/vllm#21615).
Sizes, measured with :func:`~pytest_emrd.agent.build_request` on a full history window of the
``scout`` agent (``docs/user-guide/vllm.md`` has the arithmetic): at most
:data:`~pytest_emrd.agent.HISTORY_TURNS` frames, and prompt plus ``max_tokens`` 4096 stays
under 30.5k tokens for every model, so 32768 tokens of context fit all four.
"""

from __future__ import annotations

from typing import Final

from pytest_emrd.agent._config import ModelConfig
from pytest_emrd.agent._history import HISTORY_TURNS

MAX_MODEL_LEN: Final = 32768
"""``--max-model-len`` for the four shipped open models (full window + max_tokens fits)."""
IMAGE_LIMIT_FLAG: Final = f"--limit-mm-per-prompt '{{\"image\": {HISTORY_TURNS}}}'"
CONTEXT_FLAG: Final = f"--max-model-len {MAX_MODEL_LEN}"

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
