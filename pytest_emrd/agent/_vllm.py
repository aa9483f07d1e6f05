"""Serving the open models with vLLM: the ``vllm serve`` command of each shipped open model.

:func:`serve_command` gives the command (``docs/user-guide/vllm.md`` shows the same strings; a
test keeps them equal). Reading a server's refusal back into the missing flag is preflight's job
(:func:`pytest_emrd.preflight.vllm_refusal`, run by ``emrd check``).

As the paper served them (Appendix C, Table "Inference Hyperparameters"): Qwen3-VL-32B,
Ovis2-34B and Pixtral-12B on vLLM with 4-way tensor parallelism in BFloat16, with 16,384 /
24,576 / 16,384 tokens of context (:data:`PAPER_CONTEXT`). InternVL3-14B ran on HF
Transformers in INT8 (bitsandbytes) with the model's default context; here it is served by
vLLM in BFloat16 on one GPU with the model's default context (no ``--max-model-len``): the
one stated departure, because the product talks to every model through an OpenAI-compatible
endpoint (docs/interpretation/world.md has the arithmetic and the departures).

A full 10-turn window at 512x512 (prompt estimated as in :mod:`pytest_emrd.preflight`, 500
tokens a reply) plus ``max_tokens`` 4096 needs about 12.2k tokens for Qwen3-VL (256 tokens a
frame), 22.6k for Ovis2 (1,290) and 20.2k for Pixtral (1,056): Pixtral's 16,384 holds 7 turns
of such a window, so vLLM refuses the longer requests of an episode (prompt plus
``max_tokens`` over ``--max-model-len`` is an HTTP 400). The recipe keeps the paper's figure;
``emrd check`` reports the shortfall before a run.

Flag syntax is vLLM >= 0.11.0 (the first release with Qwen3-VL): ``--limit-mm-per-prompt``
takes JSON since 0.10.0 (the older ``image=10`` form is refused, vllm-project/vllm#21615).
"""

from __future__ import annotations

from typing import Final

from pytest_emrd.agent._config import ModelConfig
from pytest_emrd.agent._history import HISTORY_TURNS

PAPER_CONTEXT: Final[dict[str, int | None]] = {
    "Qwen/Qwen3-VL-32B-Instruct": 16384,
    "AIDC-AI/Ovis2-34B": 24576,
    "mistralai/Pixtral-12B-2409": 16384,
    "OpenGVLab/InternVL3-14B": None,
}
"""``--max-model-len`` per model: the paper's context lengths (None: the model's default)."""
TENSOR_PARALLEL: Final[dict[str, int]] = {
    "Qwen/Qwen3-VL-32B-Instruct": 4,
    "AIDC-AI/Ovis2-34B": 4,
    "mistralai/Pixtral-12B-2409": 4,
    "OpenGVLab/InternVL3-14B": 1,
}
"""GPUs per model: the paper's TP=4 on L4s; InternVL3-14B on a single GPU."""
IMAGE_LIMIT_FLAG: Final = f"--limit-mm-per-prompt '{{\"image\": {HISTORY_TURNS}}}'"

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
    model = config.model_id
    context = PAPER_CONTEXT[model]
    flags = (
        *_MODEL_FLAGS[model],
        "--dtype bfloat16",
        f"--tensor-parallel-size {TENSOR_PARALLEL[model]}",
        IMAGE_LIMIT_FLAG,
        *(() if context is None else (f"--max-model-len {context}",)),
        f"--port {port}",
    )
    return " \\\n    ".join((f"vllm serve {config.model_id}", *flags))
